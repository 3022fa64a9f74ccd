"""Agent tests run torch on one thread: the models are tiny, and on a busy 2-core machine
torch's thread pool spins against the other processes (one policy step: ~1 ms vs ~0.2 s)."""

from __future__ import annotations

import pytest


@pytest.fixture(autouse=True)
def _one_torch_thread():
    torch = pytest.importorskip("torch")
    old = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(old)
