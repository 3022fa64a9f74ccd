"""HA-VLN agents trained end to end: VLN-CM and VLN-DT (the ``agents`` extra, torch).

The numpy-only parts (rendering views, demos, observations) import without torch; the models,
encoders and training need ``pip install 'havln_mj[agents]'`` (``torch==2.13.0``, CPU build).
"""
