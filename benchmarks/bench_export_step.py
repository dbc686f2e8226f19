"""One control step of the exported C controller, double build, on this machine: IFOC + speed PI +
controller (20) of Amezquita-Brooks (the ``ifoc-20`` case of ``acdrive export m4``:
im-foc-speed, 0.1 s at 50 kHz). Issue 22 asks for at most 1 us per step. Prints JSON.

    python benchmarks/bench_export_step.py [--rounds 200] [--case ifoc-20]

The inputs are those the chain saw in acdrive's loop (the replay of ``export m4``, double). A
timing program in C (gcc, the SIL library's flags without -shared) runs ``_reset`` and then the
step over all replayed samples, ``--rounds`` times, each round timed with
clock_gettime(CLOCK_MONOTONIC); per round the mean time of one step. Reported: min, median and
max over the rounds (ns per step), the load average, and whether the median is within 1 us.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import tempfile
from pathlib import Path

from acdrive.export._cost import case_export, replay_inputs
from acdrive.export._sil import CFLAGS, find_compiler

TIMER_C = r"""#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "{header}"

int main(int argc, char **argv)
{{
    const long samples = {samples}L;
    const int rounds = atoi(argv[2]);
    {c}_inputs *replay = malloc(sizeof({c}_inputs) * (size_t)samples);
    {c}_params p;
    {c}_state s;
    {c}_outputs out;
    FILE *f = fopen(argv[1], "rb");
    if (argc < 3 || replay == NULL || f == NULL
        || fread(replay, sizeof({c}_inputs), (size_t)samples, f) != (size_t)samples) {{
        return 1;
    }}
    fclose(f);
    {c}_set_params(&p);
    for (int r = 0; r < rounds; ++r) {{
        struct timespec a, b;
        {c}_reset(&s);
        clock_gettime(CLOCK_MONOTONIC, &a);
        for (long k = 0; k < samples; ++k) {{
            {c}_step((double)k * p.sample_time, &p, &s, &replay[k], &out);
        }}
        clock_gettime(CLOCK_MONOTONIC, &b);
        printf("%.3f\n", ((b.tv_sec - a.tv_sec) * 1e9 + (b.tv_nsec - a.tv_nsec)) / samples);
    }}
    free(replay);
    return 0;
}}
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default="ifoc-20")
    parser.add_argument("--rounds", type=int, default=200)
    args = parser.parse_args()
    gcc = find_compiler()
    _, setup, drive, initial, held, export = case_export(args.case)
    (replay,), samples = replay_inputs(setup, drive, initial, held, export)
    (model,) = export.chains
    c = model.chain.name
    with tempfile.TemporaryDirectory(prefix="acdrive-bench-") as scratch:
        folder = Path(scratch)
        (folder / export.header_name).write_text(export.header)
        (folder / export.source_name).write_text(export.source)
        (folder / "replay.bin").write_bytes(replay)
        (folder / "timer.c").write_text(
            TIMER_C.format(header=export.header_name, c=c, samples=samples)
        )
        flags = [f for f in CFLAGS if f not in ("-fPIC", "-shared")]
        subprocess.run([gcc, *flags, "-o", str(folder / "timer"), str(folder / "timer.c"),
                        str(folder / export.source_name), "-lm"], check=True)  # fmt: skip
        done = subprocess.run([str(folder / "timer"), str(folder / "replay.bin"),
                               str(args.rounds)], capture_output=True, text=True, check=True)  # fmt: skip
    per_step = [float(x) for x in done.stdout.split()]
    median = statistics.median(per_step)
    print(json.dumps({
        "case": args.case,
        "scenario": setup.name,
        "build": "double, gcc " + " ".join(flags),
        "samples_per_round": samples,
        "rounds": len(per_step),
        "ns_per_step": {"min": min(per_step), "median": median, "max": max(per_step)},
        "target_ns": 1000.0,
        "median_within_target": median <= 1000.0,
        "load_average_1min": os.getloadavg()[0],
        "cores": os.cpu_count(),
    }, indent=2))  # fmt: skip


if __name__ == "__main__":
    main()
