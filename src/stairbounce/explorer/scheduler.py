"""The explorer's scheduler: every session's work, one bounded slice at a time.

All renders and taps of all browser sessions run on one worker thread, as
generators whose every ``next()`` computes one slice (a band of rows of a
render, bounded by :data:`~stairbounce.explorer.view.SLICE_WORK` potential map
steps; the word, then the orbit diagram of a tap).  Each slice uses every core
(the numba kernels are parallel), and only one thread ever enters them:
numba's fallback threading layer must not be entered from two threads at once.

Which job gets the next slice: the one whose session has used the least
compute time recently (the sum of its slices' times, decaying with a time
constant of :data:`USAGE_DECAY` seconds), oldest first among equals.  So a
request from a session that was idle (a tap, a small view) runs before the
next slice of another session's long render, waiting at most for the slice
in progress; sessions that keep the worker busy take turns, and none
starves (a waiting session's usage decays while the others' grows; ranking
jobs by their own attained time instead let a session that kept sending
small requests hold back a longer one for minutes).  The job that ran the
last slice keeps the worker while its session's recent compute time is
within :data:`QUANTUM` of the least: requests of equal size then finish one
after another (the first after one render's time, the fifth after five)
instead of all together at the end, as slice-by-slice sharing did, and a
request from the least busy session waits at most ``QUANTUM`` and one slice.
A session has at most
one job of each kind: a new request supersedes its own pending one, and a
job whose session is gone (``alive()`` false) is dropped before its next
slice.
"""

from __future__ import annotations

import itertools
import math
import threading
import time
from collections.abc import Generator
from dataclasses import dataclass, field
from typing import Any

__all__ = ["Job", "Scheduler", "USAGE_DECAY"]

USAGE_DECAY = 5.0
"""Time constant (s) of the decay of a session's recent compute time."""

QUANTUM = 0.25
"""The job that ran the last slice keeps the worker while its session's
recent compute time is at most this much (s) above the least of the others."""


@dataclass(eq=False)
class Job:
    """One request: ``work`` is a generator (one slice per ``next()``, the
    result as its return value).  Callbacks run on the worker thread:
    ``on_slice(value)`` after each slice, ``on_done(result, error, job)`` once."""

    owner: object
    kind: str
    work: Generator[Any, None, Any]
    on_slice: object = None
    on_done: object = None
    alive: object = None
    seq: int = 0
    attained: float = 0.0
    started: bool = False
    cancelled: bool = False
    submitted: float = field(default_factory=time.monotonic)


class Scheduler:
    """Scheduler() -> runs :class:`Job` slices on one daemon worker thread.

    ``submit`` never blocks; ``cancel(owner)`` drops an owner's jobs at once
    (a slice already running finishes, then its job is closed).  With
    ``thread=False`` nothing runs until :meth:`run_all` (tests); ``quantum``
    (s, default :data:`QUANTUM`) is how far above the least used session the
    job under way may go before it yields the worker.
    """

    def __init__(self, name: str = "stairbounce-explorer", thread: bool = True, quantum: float = QUANTUM):
        self._cv = threading.Condition()
        self._jobs: list[Job] = []
        self._running: Job | None = None
        self._last: Job | None = None  # ran the last slice and is not done
        self.quantum = quantum  # 0: the least used session's job every slice
        self._seq = itertools.count()
        self._usage: dict[int, tuple[float, float]] = {}  # id(owner) -> (usage, at time)
        self._name = name
        self._thread: threading.Thread | None = None
        self._use_thread = thread  # False: jobs run only in run_all() (tests)
        self.slices = 0  # slices run so far (tests, benchmarks)

    # ------------------------------------------------------------- requests

    def submit(self, owner, kind, work, on_slice=None, on_done=None, alive=None) -> Job:
        """Queue ``work`` (a generator) for ``owner``; supersedes the owner's
        job of the same ``kind``.  Returns the :class:`Job`."""
        job = Job(owner, kind, work, on_slice, on_done, alive, next(self._seq))
        with self._cv:
            self._drop(lambda j: j.owner is owner and j.kind == kind)
            self._jobs.append(job)
            self._ensure_thread()
            self._cv.notify()
        return job

    def cancel(self, owner, kind=None) -> None:
        """Drop every job of ``owner`` (of ``kind`` only, if given)."""
        with self._cv:
            self._drop(lambda j: j.owner is owner and (kind is None or j.kind == kind))

    def ahead_of(self, job: Job) -> int:
        """How many other sessions' jobs are queued or running besides ``job``."""
        with self._cv:
            others = [j for j in self._jobs if j.owner is not job.owner]
            if self._running is not None and self._running.owner is not job.owner and self._running not in others:
                others.append(self._running)
            return len(others)

    def busy(self) -> bool:
        with self._cv:
            return bool(self._jobs) or self._running is not None

    def _drop(self, match):
        # under the lock; the running job is closed by the worker after its slice
        keep = []
        for j in self._jobs:
            if match(j):
                j.cancelled = True
                if j is not self._running:
                    j.work.close()
            else:
                keep.append(j)
        self._jobs = keep
        if self._running is not None and match(self._running):
            self._running.cancelled = True

    # ---------------------------------------------------------------- worker

    def _ensure_thread(self):
        if not self._use_thread:
            return
        if self._thread is None or not self._thread.is_alive():
            self._thread = threading.Thread(target=self._loop, name=self._name, daemon=True)
            self._thread.start()

    def _pick(self) -> Job | None:
        """Under the lock: drop dead owners' jobs, return the next to run."""
        live = []
        for j in self._jobs:
            if j.alive is not None and not _safe(j.alive):
                j.cancelled = True
                j.work.close()
            else:
                live.append(j)
        self._jobs = live
        now = time.monotonic()
        owners = {id(j.owner) for j in live}
        for k in [k for k, (u, t) in self._usage.items() if k not in owners and u * _decay(now - t) < 1e-3]:
            del self._usage[k]  # forgotten: no job and no recent use
        if not live:
            return None
        best = min(live, key=lambda j: (self.usage(j.owner, now), j.seq))
        last = self._last
        if (last is not None and last is not best and last in live  # jobs compare by identity
                and self.usage(last.owner, now) <= self.usage(best.owner, now) + self.quantum):
            return last  # finish what is under way rather than share the worker slice by slice
        return best

    def usage(self, owner, now=None) -> float:
        """The owner's recent compute time in seconds (decayed)."""
        u, t = self._usage.get(id(owner), (0.0, 0.0))
        return u * _decay((time.monotonic() if now is None else now) - t)

    def _loop(self):
        while True:
            with self._cv:
                while not self._jobs:
                    self._cv.wait()
            self.run_next()

    def run_next(self) -> bool:
        """Run one slice of the job :meth:`_pick` chooses on this thread (the
        worker's loop; tests); False when there is none."""
        with self._cv:
            job = self._pick()
            if job is None:
                return False
            self._running = job
        self.run_slice(job)
        return True

    def run_slice(self, job: Job) -> None:
        """Run one slice of ``job`` on this thread (the worker's loop; tests)."""
        t0 = time.perf_counter()
        done, result, error = False, None, None
        try:
            value = next(job.work)
        except StopIteration as stop:
            done, result = True, stop.value
        except Exception as exc:  # reported to the page; the server keeps going
            done, error = True, exc
        dt = time.perf_counter() - t0
        with self._cv:
            self.slices += 1
            job.attained += dt
            now = time.monotonic()
            self._usage[id(job.owner)] = (self.usage(job.owner, now) + dt, now)
            job.started = True
            self._running = None
            self._last = None if done or job.cancelled else job
            cancelled = job.cancelled
            if done and job in self._jobs:
                self._jobs.remove(job)
        if cancelled:
            job.work.close()
            return
        if done:
            if job.on_done is not None:
                _safe(job.on_done, result, error, job)
        elif job.on_slice is not None:
            _safe(job.on_slice, value)

    def run_all(self) -> None:
        """Run every queued job to its end on this thread (tests, no server)."""
        while self.run_next():
            pass


def _decay(age):
    return math.exp(-max(0.0, age) / USAGE_DECAY)


def _safe(fn, *args):
    """Call a callback; a failing one (a closed page) must not stop the worker."""
    try:
        return fn(*args)
    except Exception:
        return False
