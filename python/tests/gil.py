"""Whether a call lets other Python threads run while it works."""
import sys
import threading
import time

# A call holding the GIL leaves the measuring thread only the moments it spends in
# Python bytecode around the work (under 1 % of a long call, measured); a call that
# releases it leaves the measuring thread whatever share of a core the scheduler gives:
# all of it on an idle machine, a third with six threads busy on two cores. The bound
# sits between the two, far from each, so scheduler hiccups cannot decide the outcome.
RELEASED_SHARE = 0.1


def gil_free_share(work, repeat=3):
    """(share of the calls' time during which this thread ran Python, the calls' total
    time), `work` called `repeat` times on another thread. This thread spins reading the
    clock; an interval between two readings counts as running when shorter than 1 ms
    (longer ones are waits: for the GIL, or for a core)."""
    inside = [False]
    done = threading.Event()
    calls, error = [], []

    def run():
        try:
            for _ in range(repeat):
                inside[0] = True
                t0 = time.perf_counter()
                work()
                calls.append(time.perf_counter() - t0)
                inside[0] = False
        except Exception as e:  # raised here, after the measurement
            error.append(e)
        finally:
            inside[0] = False
            done.set()

    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-4)  # a thread holding the GIL in bytecode yields it at once
    try:
        ran = 0.0
        t = threading.Thread(target=run)
        t.start()
        last = time.perf_counter()
        while not done.is_set():
            now = time.perf_counter()
            if inside[0] and now - last < 1e-3:
                ran += now - last
            last = now
        t.join()
    finally:
        sys.setswitchinterval(interval)
    if error:
        raise error[0]
    total = sum(calls)
    return ran / total, total
