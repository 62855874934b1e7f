"""What a Python call adds over the same call in Rust: TROLSpeed (a small CAT1 command)
against the embedded controller, made N times from Python and N times from Rust (through
the same connection), in alternating rounds; prints the medians and their difference.

    python crates/trol-py/bench_overhead.py [N] [ROUNDS]
"""

import json
import statistics
import sys
import time

import trol

n = int(sys.argv[1]) if len(sys.argv) > 1 else 3000
rounds = int(sys.argv[2]) if len(sys.argv) > 2 else 7

with trol.Robot.open("sim") as robot:
    python_us, rust_us = [], []
    for _ in range(rounds):
        t = time.perf_counter()
        for _ in range(n):
            robot.speed(50)
        python_us.append((time.perf_counter() - t) / n * 1e6)
        rust_us.append(robot._rust_loop(n, 50) / n * 1e6)
    py, rs = statistics.median(python_us), statistics.median(rust_us)
    # The binding alone, without the line: a call refused by its argument check (the GIL
    # released, the lock taken, the record checked, trol.ArgumentError raised).
    t = time.perf_counter()
    for _ in range(n):
        try:
            robot.ma([0.0] * 7)
        except trol.ArgumentError:
            pass
    refused_us = (time.perf_counter() - t) / n * 1e6
    print(
        json.dumps(
            {
                "calls_per_round": n,
                "rounds": rounds,
                "python_us_per_call": round(py, 2),
                "rust_us_per_call": round(rs, 2),
                "added_us_per_call": round(py - rs, 2),
                "added_us_per_call_best_rounds": round(min(python_us) - min(rust_us), 2),
                "binding_alone_us_per_call": round(refused_us, 2),
            },
            indent=2,
        )
    )
