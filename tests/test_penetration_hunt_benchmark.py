"""The penetration hunt's time cap (``benchmarks/penetration_hunt.py``)."""

import signal
import sys
import types
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import penetration_hunt  # noqa: E402


def _alarm_that_fires_at_its_reset(monkeypatch):
    """``signal`` in the hunt's module with an ``alarm`` whose reset (``alarm(0)``) first
    delivers the pending SIGALRM: the cap running out just as a run ends."""
    def alarm(seconds):
        if seconds == 0:
            signal.raise_signal(signal.SIGALRM)
        return 0

    fake = types.SimpleNamespace(signal=signal.signal, SIGALRM=signal.SIGALRM, alarm=alarm)
    monkeypatch.setattr(penetration_hunt, "signal", fake)


def test_a_cap_that_runs_out_as_a_run_ends_is_a_timeout_not_a_crash(monkeypatch):
    """The cap's signal between a run's end and the alarm's reset escaped ``run_one`` and
    ended the whole hunt (seen once by a helper, 2026-12-07)."""
    _alarm_that_fires_at_its_reset(monkeypatch)
    end, message = penetration_hunt.run_one(lambda spec: None, {}, 5.0)
    assert end == "timeout" and "over 5" in message


def test_a_run_within_its_cap_completes_and_leaves_no_handler():
    before = signal.getsignal(signal.SIGALRM)
    assert penetration_hunt.run_one(lambda spec: None, {}, 5.0) == ("completed", "")
    assert signal.getsignal(signal.SIGALRM) == before
