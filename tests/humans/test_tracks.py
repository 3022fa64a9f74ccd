"""Tabulated pelvis tracks: read unrolled or wrapped, they are the crowd's own positions."""

from __future__ import annotations

import numpy as np
import pytest

from havln_mj.humans.body import random_body
from havln_mj.humans.clip import Clip
from havln_mj.humans.crowd import Crowd, Person
from havln_mj.humans.tracks import UNROLLED_S


def _clip(root: np.ndarray, loop_start: int = 0, fps: float = 30.0) -> Clip:
    return Clip(root, fps, positions=np.zeros((len(root), 24, 3)), loop_start=loop_start)


@pytest.fixture(scope="module")
def crowd():
    """A loop that ends where it starts, one that jumps back, an intro then a loop, a clip
    that plays once then holds, a single frame; at different rates, headings and starts."""
    t = np.linspace(0.0, 1.0, 31)
    circle = np.stack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t), np.ones_like(t)], 1)
    line = np.stack([np.zeros(45), np.linspace(0.0, 2.0, 45), np.ones(45)], 1)
    clips = [
        _clip(circle),
        _clip(line, fps=24.0),  # walks 2 m, then jumps back to where it began
        _clip(np.concatenate([line[:20], circle + line[19]]), loop_start=20),
        _clip(line, loop_start=44, fps=60.0),  # plays once, then holds its last frame
        _clip(line[:1]),
    ]
    rng = np.random.default_rng(0)
    people = [
        Person(random_body(rng), clip, rng.uniform(-5, 5, 3), rng.uniform(0, 6), "x", start=s)
        for clip, s in zip(clips, (0.0, 0.3, 0.05, 1.1, 0.0), strict=True)
    ]
    return Crowd(people)


def _times() -> np.ndarray:
    """Dense times over the unrolled span and past it, on both sides of every frame (a
    loop's wrap included; exactly at a wrap, where a jumping loop has two values, the
    formulations may round to either)."""
    grid = np.arange(0.0, UNROLLED_S + 30.0, 1.0 / 240.0)
    return np.sort(np.concatenate([grid + 1e-7, grid[1:] - 1e-7]))


@pytest.mark.parametrize("people", [None, [1, 3], [4]])
def test_a_table_reads_the_crowds_own_pelvis_positions(crowd, people):
    table, times = crowd.pelvis_table(), _times()
    direct = crowd.positions(times, None if people is None else np.array(people))
    expected = (direct[..., 0] + 1j * direct[..., 1]).T  # (people, times)
    inside = times <= UNROLLED_S
    unrolled = table.xy(times[inside], people=people, latest=float(times[inside].max()))
    wrapped = table.xy(times, people=people)
    np.testing.assert_allclose(unrolled, expected[:, inside], rtol=0, atol=1e-9)
    np.testing.assert_allclose(wrapped, expected, rtol=0, atol=1e-9)
