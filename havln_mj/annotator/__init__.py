"""``havln_mj annotate``: a local web page to place people in a scan as HA3D placements.

The page (served on localhost by :class:`~havln_mj.annotator.server.AnnotationServer`) shows
the scan's map and the agent's view from any viewpoint; people are placed on viewpoints, moved
(dragged) and deleted, given an activity of their room's catalog, a motion model and a facing,
and their motion is previewed as a short H.264 clip. Placements are saved to and loaded from
HA3D's ``human_motion_text.json`` format, which ``Simulator(humans=True,
human_placements=...)`` reads. Modules: :mod:`~havln_mj.annotator.placements` (the file
format), :mod:`~havln_mj.annotator.plan` (the map's data), :mod:`~havln_mj.annotator.session`
(state and pictures), :mod:`~havln_mj.annotator.server` (HTTP), :mod:`~havln_mj.annotator.command`
(the CLI) and :mod:`~havln_mj.annotator.browser` (a headless Chromium to drive the page).
"""
