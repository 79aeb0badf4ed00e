# SPDX-License-Identifier: GPL-3.0-or-later
"""Progress callbacks, cancellation (by the callback and by Ctrl-C), the GIL released while a
stage runs. The "long" cloud is sized so normals take well over the 50 ms polling period; the
checks compare counts, not times, and the Ctrl-C tests send SIGINT once the stage has started,
with Python's handler installed by the test (so they hold in a background job and under load)."""
import os
import signal
import threading
import time

import pytest

import pointsurf
from conftest import sphere_points


@pytest.fixture(scope="module")
def big():
    return pointsurf.PointCloud(sphere_points(200_000, seed=3))


def test_progress_is_called_in_order_and_ends_at_one(cloud):
    seen = []
    pointsurf.normals(cloud, progress=lambda f: seen.append(f))
    assert seen and seen[-1] == pytest.approx(1.0)
    assert all(0.0 <= f <= 1.0 for f in seen)
    assert seen == sorted(seen)


def test_progress_returning_false_cancels(big):
    calls = []

    def stop(f):
        calls.append(f)
        return False
    with pytest.raises(pointsurf.CancelledError, match="normals: cancelled"):
        pointsurf.normals(big, progress=stop)
    assert len(calls) == 1
    assert issubclass(pointsurf.CancelledError, pointsurf.ComputeError)


def test_exception_in_callback_propagates(big):
    def boom(f):
        raise ValueError("from the callback")
    with pytest.raises(ValueError, match="from the callback"):
        pointsurf.normals(big, progress=boom)


def test_gil_is_released_during_a_stage(big):
    ticks, running = [0], [True]

    def spin():
        while running[0]:
            ticks[0] += 1
    t = threading.Thread(target=spin)
    t.start()
    try:
        time.sleep(0.01)
        start = ticks[0]
        out = pointsurf.normals(big, k=20)
        during = ticks[0] - start
    finally:
        running[0] = False
        t.join()
    assert len(out.normals) == len(big)
    # Held GIL: the spinner gets a slice every 5 ms switch interval at best, i.e. a handful of
    # ticks per switch; released: it spins freely (millions of ticks per second).
    assert during > 100_000, during


@pytest.fixture(scope="module")
def big_oriented(big):
    return pointsurf.normals(big, k=10, orient="none")


@pytest.fixture
def sigint_handled():
    """SIGINT raises KeyboardInterrupt in the main thread during the test, whatever the process
    inherited: a background job of a non-interactive shell (`cmd &`) starts with SIGINT ignored,
    and Python then leaves it ignored. The handler also sets the Event this yields, so a test
    knows when Python has run it. The previous disposition is restored afterwards."""
    handled = threading.Event()

    def handler(signum, frame):
        handled.set()
        signal.default_int_handler(signum, frame)  # raises KeyboardInterrupt
    previous = signal.signal(signal.SIGINT, handler)
    try:
        yield handled
    finally:
        signal.signal(signal.SIGINT, previous if previous is not None else signal.SIG_DFL)


def test_ctrl_c_cancels_a_running_stage(big_oriented, sigint_handled):
    # SIGINT sent from the stage's first progress report, so the stage is running; the report then
    # waits until Python has run the handler. Python runs it in the main thread, which waits for
    # the stage taking the GIL every 50 ms to check signals: the handler's KeyboardInterrupt
    # cancels the stage and comes out of the call, however loaded the machine is.
    calls = []

    def progress(fraction):
        calls.append(fraction)
        if len(calls) == 1:
            os.kill(os.getpid(), signal.SIGINT)
            assert sigint_handled.wait(120), "the main thread did not run the SIGINT handler during the stage"
        return True
    with pytest.raises(KeyboardInterrupt):
        pointsurf.reconstruct(big_oriented, progress=progress)
    assert sigint_handled.is_set()


def test_ctrl_c_cancels_a_running_stage_without_callback(big_oriented, sigint_handled):
    # Without a callback there is no report to hook: SIGINT is sent once the call has started the
    # stage's worker thread (a thread of this process that was not there before the call), so the
    # main thread is inside the call, waiting on the stage. KeyboardInterrupt comes out of the call
    # (from the wait when it sees the signal first, right after it when the stage ended first).
    if not os.path.isdir("/proc/self/task"):
        pytest.skip("needs /proc/self/task (Linux) to see the stage's thread start")
    go, done, before = threading.Event(), threading.Event(), set()

    def interrupt_when_the_stage_runs():
        go.wait()
        while not done.is_set():
            if set(os.listdir("/proc/self/task")) - before:
                os.kill(os.getpid(), signal.SIGINT)
                return
            time.sleep(0.001)
    sender = threading.Thread(target=interrupt_when_the_stage_runs)
    sender.start()
    before.update(os.listdir("/proc/self/task"))  # the sender's thread included
    go.set()
    try:
        with pytest.raises(KeyboardInterrupt):
            pointsurf.reconstruct(big_oriented)
    finally:
        done.set()
        sender.join()
    assert sigint_handled.is_set()
