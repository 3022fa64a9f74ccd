"""CtrlC: a Ctrl-C that Python cannot raise is remembered and kept off the terminal."""

from __future__ import annotations

import signal
import subprocess
import sys

import pytest

from havln_mj.ctrl_c import CtrlC

LOST = """
import gc, signal, sys, weakref
from havln_mj.ctrl_c import CtrlC

handler, hook = signal.getsignal(signal.SIGINT), sys.unraisablehook
ctrl_c = CtrlC()
ctrl_c.install()
class Thing: pass
def callback(ref): raise {exc}
thing = Thing()
ref = weakref.ref(thing, callback)
del thing
gc.collect()
ctrl_c.restore()
print(ctrl_c.seen, signal.getsignal(signal.SIGINT) is handler and sys.unraisablehook is hook)
"""


@pytest.mark.parametrize("exc, seen", [("KeyboardInterrupt", True), ("ValueError('x')", False)])
def test_a_lost_ctrl_c_is_remembered_quietly_and_other_errors_still_print(exc, seen):
    # The import system's weakref callbacks are where a Ctrl-C is lost in practice.
    code = LOST.format(exc=exc)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == [str(seen), "True"]
    assert ("Traceback" in proc.stderr) is not seen


def test_a_raised_ctrl_c_is_remembered_too():
    ctrl_c = CtrlC()
    ctrl_c.install()
    try:
        with pytest.raises(KeyboardInterrupt):
            signal.raise_signal(signal.SIGINT)
    finally:
        ctrl_c.restore()
    assert ctrl_c.seen
