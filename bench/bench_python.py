#!/usr/bin/env python3
"""Timings of the Python module against numpy and against the C++ calls it wraps
(docs/benchmarks.md, "Python").

  eval_sh     10^6 directions at order 4 (float64), against a vectorised numpy closed form
  rotate      10^6 order-3 RGB vectors (float32): one matrix per splat or per vector
              (rotate_batch), on one thread against the C++ BM_RotateBatch/float/auto/large/3
              of bench_rotation (which builds each matrix from a quaternion; the module
              checks each one instead), and one matrix for the whole scene
  overhead    one order-3 vector per call, microseconds per call
  project_env a 4096 x 2048 RGB float32 image at order 3, one thread, against the C++
              BM_ProjectEquirect/3 of bench_env

Run: PYTHONPATH=build/python /usr/bin/python3 bench/bench_python.py [--build build]
(with the build folder, the two C++ benchmarks are run too, when built).
"""
import argparse
import json
import math
import pathlib
import subprocess
import time

import numpy as np

import shtool


def best(f, repeat=5, clock=time.perf_counter):
    """Fastest of `repeat` runs, seconds (the least disturbed by other load). One-thread
    cases pass clock=time.process_time: CPU time, as Google Benchmark's items_per_second
    counts it, so that both sides are measured alike on a loaded machine."""
    times = []
    for _ in range(repeat):
        t = clock()
        f()
        times.append(clock() - t)
    return min(times)


CPU = time.process_time


def numpy_order4(d):
    """Bands 0..3 of docs/conventions.md as numpy expressions."""
    x, y, z = d[:, 0], d[:, 1], d[:, 2]
    xx, yy, zz = x * x, y * y, z * z
    c = [0.28209479177387814, 0.48860251190291992, 1.0925484305920791, 0.31539156525252001, 0.54627421529603954,
         0.59004358992664351, 2.8906114426405541, 0.45704579946446574, 0.37317633259011539, 1.4453057213202770]
    return np.stack([np.full_like(x, c[0]), -c[1] * y, c[1] * z, -c[1] * x, c[2] * x * y, -c[2] * y * z,
                     c[3] * (3 * zz - 1), -c[2] * x * z, c[4] * (xx - yy), -c[5] * y * (3 * xx - yy),
                     c[6] * x * y * z, -c[7] * y * (5 * zz - 1), c[8] * z * (5 * zz - 3), -c[7] * x * (5 * zz - 1),
                     c[9] * z * (xx - yy), -c[5] * x * (xx - 3 * yy)], axis=1)


def cpp_benchmark(build, program, pattern):
    exe = pathlib.Path(build) / "bench" / program
    if not exe.exists():
        return None
    r = subprocess.run([str(exe), f"--benchmark_filter={pattern}", "--benchmark_format=json",
                        "--benchmark_min_time=0.5"], capture_output=True, text=True, check=True)
    return json.loads(r.stdout)["benchmarks"][0]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", help="build folder with bench/bench_rotation and bench/bench_env")
    args = ap.parse_args()
    rng = np.random.default_rng(1)
    rows = []

    d = rng.normal(size=(1_000_000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    np.testing.assert_allclose(shtool.eval_sh(4, d), numpy_order4(d), atol=1e-14)
    rows.append(("eval_sh, 10^6 dirs, order 4, float64, all cores", best(lambda: shtool.eval_sh(4, d)) * 1e3, "ms"))
    rows.append(("eval_sh, the same, 1 thread (CPU time)", best(lambda: shtool.eval_sh(4, d, threads=1), clock=CPU) * 1e3,
                 "ms"))
    rows.append(("numpy closed form, the same (CPU time)", best(lambda: numpy_order4(d), clock=CPU) * 1e3, "ms"))

    sh = rng.normal(size=(1_000_000, 3, 9)).astype(np.float32)
    q = rng.normal(size=(1_000_000, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    per_splat = shtool.quat_to_matrix(q).astype(np.float32)  # (S, 3, 3): one per splat, for its 3 channels
    per_vector = np.repeat(per_splat, 3, axis=0)
    out = np.empty_like(sh)
    t_batch = best(lambda: shtool.rotate(sh, per_splat, out=out, threads=1), 3, CPU)
    rows.append(("rotate, 10^6 RGB order 3 float32, a matrix per splat, 1 thread (CPU time)",
                 t_batch / 3e6 * 1e9, "ns per vector"))
    rows.append(("rotate, the same, all cores", best(lambda: shtool.rotate(sh, per_splat, out=out), 3) / 3e6 * 1e9,
                 "ns per vector"))
    t_batch = best(lambda: shtool.rotate(sh.reshape(-1, 9), per_vector, out=out.reshape(-1, 9), threads=1), 3, CPU)
    rows.append(("rotate, 3 x 10^6 order 3 float32 vectors, a matrix per vector, 1 thread (CPU time)",
                 t_batch / 3e6 * 1e9, "ns per vector"))
    one = shtool.quat_to_matrix(q[0]).astype(np.float32)
    rows.append(("rotate, 10^6 RGB order 3 float32, one matrix, 1 thread (CPU time)",
                 best(lambda: shtool.rotate(sh, one, out=out, threads=1), clock=CPU) / 3e6 * 1e9, "ns per vector"))
    rows.append(("rotate, the same, all cores", best(lambda: shtool.rotate(sh, one, out=out)) / 3e6 * 1e9,
                 "ns per vector"))
    cpp = cpp_benchmark(args.build, "bench_rotation", "BM_RotateBatch/float/auto/large/3$") if args.build else None
    if cpp:
        rows.append(("C++ rotate_batch (BM_RotateBatch/float/auto/large/3), 1 thread (CPU time)",
                     1e9 / cpp["items_per_second"], "ns per vector"))

    f = rng.normal(size=9)
    r = shtool.quat_to_matrix(q[1])
    calls = 20000
    t = best(lambda: [shtool.rotate(f, r) for _ in range(calls)], 3)
    rows.append(("rotate, one order-3 vector per call (float64, wall time)", t / calls * 1e6, "us per call"))
    t = best(lambda: [shtool.eval_sh(3, d[0]) for _ in range(calls)], 3)
    rows.append(("eval_sh, one direction per call, order 3 (wall time)", t / calls * 1e6, "us per call"))

    image = rng.uniform(size=(2048, 4096, 3)).astype(np.float32)
    rows.append(("project_env 4096 x 2048 RGB float32, order 3, 1 thread (CPU time)",
                 best(lambda: shtool.project_env(image, 3, threads=1), 3, CPU) * 1e3, "ms"))
    rows.append(("project_env, the same, all cores", best(lambda: shtool.project_env(image, 3), 3) * 1e3, "ms"))
    cpp = cpp_benchmark(args.build, "bench_env", "BM_ProjectEquirect/3$") if args.build else None
    if cpp:
        rows.append(("C++ project_equirect (BM_ProjectEquirect/3), 1 thread (CPU time)", cpp["cpu_time"],
                     cpp["time_unit"]))

    print("| case | time | unit |\n| --- | --- | --- |")
    for name, value, unit in rows:
        print(f"| {name} | {value:.3g} | {unit} |")


if __name__ == "__main__":
    main()
