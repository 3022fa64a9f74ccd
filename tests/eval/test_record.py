"""``eval --record N``: a video and a top-down map of the first N evaluated instructions."""

from __future__ import annotations

import json

import cv2

from havln_mj.commands.evaluate import main


def test_record_writes_a_video_and_a_map_that_match_the_evaluation(tmp_path):
    out = tmp_path / "rec"
    argv = "--scenes proc-0 --per-scene 1 --agent oracle --protocol ha3d --record 2 --seed 4"
    assert main([*argv.split(), "--out", str(out)]) == 0
    runs = [json.loads(x) for x in (out / "instructions.jsonl").read_text().splitlines()]
    reports = sorted((out / "recordings").glob("*.json"))
    assert [p.stem for p in reports] == sorted(r["instr_id"] for r in runs[:2])
    for path, run in zip(reports, sorted(runs[:2], key=lambda r: r["instr_id"]), strict=True):
        report = json.loads(path.read_text())
        assert report["matches_evaluation"]
        assert report["steps"] == len(run["steps"]) - 1
        assert report["collided_steps"] == sum(s[3] for s in run["steps"])
        video = cv2.VideoCapture(report["video"])
        assert int(video.get(cv2.CAP_PROP_FRAME_COUNT)) == report["frames"] > 0
        assert video.read()[1].shape[1] == 320
        image = cv2.imread(report["map"])
        assert image is not None and image.shape[0] > 200
