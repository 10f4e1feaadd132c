"""The mutation fuzz of tests/bridge/test_fuzz_exchange.py at a large count, for the closing note of issue 17.

Writes N damaged copies per format of a clean model (the test's filleted box: deleted lines, swapped
references, cuts at an entity boundary with the trailer put back; tests/bridge/corrupt_files.py), then

* reads all of them with ``occsurf inspect DIR --jsonl`` (one worker for the folder, ``--timeout``),
* reads each *in-process* inside a worker (the isolated reader's own job), so a crash inside OCC is seen
  as the death of that worker and counted, not as the end of this script,

and prints the counts: read cleanly, read with warnings, refused, crashed, timed out; plus the number of
files whose face count differs from the clean model's without a warning (must be 0) and of crashes
(must be 0). Exit status 1 if either is not 0.

    python benchmarks/bench_fuzz_exchange.py [--n 300] [--seed 0] [--keep DIR]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from occsurf.bridge.exchange.step_iges import READ_JOB, READ_PRELOAD, read_iges, read_step, write_iges, write_step  # noqa: E402
from occsurf.bridge.isolation import run_jobs  # noqa: E402
from tests.bridge import corrupt_files as C  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=300, help="mutated files per format (default 300)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--keep", type=Path, help="write the files here (default: a temporary folder)")
    ap.add_argument("--formats", nargs="+", choices=("step", "iges"), default=["step", "iges"])
    args = ap.parse_args()
    import cadquery as cq

    box = cq.Workplane().box(1, 2, 3).edges("|Z").fillet(0.2).val().wrapped
    rng = np.random.default_rng(args.seed)
    tmp = tempfile.TemporaryDirectory(prefix="occsurf-fuzz-")
    root = args.keep or Path(tmp.name)
    bad = 0
    for fmt, writer, reader, suffix in (("step", write_step, read_step, ".step"), ("iges", write_iges, read_iges, ".igs")):
        if fmt not in args.formats:
            rng.choice(["delete", "swap", "cut"], size=args.n), rng.integers(0, 10**6, size=(args.n, 2))
            continue  # the same random draws: --formats iges gives the files of a full run
        folder = root / fmt
        folder.mkdir(parents=True, exist_ok=True)
        clean = writer(root / f"clean{suffix}", [box])
        n_clean = len(reader(clean).faces)
        data = clean.read_bytes()
        kinds = rng.choice(["delete", "swap", "cut"], size=args.n)
        ab = rng.integers(0, 10**6, size=(args.n, 2))
        paths = [C.write(folder, f"{k:04d}_{kind}{suffix}", C.mutate(fmt, data, kind, int(a), int(b)))
                 for k, (kind, (a, b)) in enumerate(zip(kinds, ab))]
        counts: Counter = Counter(files=len(paths))
        t0 = time.perf_counter()
        proc = subprocess.run([sys.executable, "-m", "occsurf.bridge.cli", "inspect", str(folder), "--jsonl",
                               "--samples", "5", "--timeout", "120"], capture_output=True, cwd=REPO)
        t_inspect = time.perf_counter() - t0
        if b"Traceback" in proc.stderr or proc.returncode not in (0, 2) or proc.returncode < 0:
            print(f"{fmt}: inspect exit {proc.returncode}, stderr tail: {proc.stderr[-500:]!r}")
            bad += 1
        for line in proc.stdout.splitlines():
            f = json.loads(line)
            if f["error"] is not None:
                counts["inspect " + ("crashed" if "crashed" in f["error"] else
                                     "timeout" if "longer than" in f["error"] else "refused")] += 1
                continue
            counts["inspect " + ("warned" if f["warnings"] else "clean")] += 1
            if f["n_faces"] != n_clean and not f["warnings"]:
                counts["inspect silent face-count change"] += 1
        t0 = time.perf_counter()
        items = [{"path": str(p), "format": fmt, "out": str(p) + ".brep"} for p in paths]
        for p, o in zip(paths, run_jobs(READ_JOB, items, timeout=120, preload=READ_PRELOAD)):
            counts[f"in-process {o.status}"] += 1
            if o.status in ("crashed", "timeout"):
                print(f"{fmt}: in-process read of {p.name}: {o.status} ({o.exit_reason})")
            if o.status == "ok" and o.value["faces"] != n_clean and not o.value["warnings"]:
                counts["in-process silent face-count change"] += 1
        t_inproc = time.perf_counter() - t0
        bad += counts["in-process crashed"] + counts["inspect crashed"]
        bad += counts["in-process silent face-count change"] + counts["inspect silent face-count change"]
        print(f"{fmt.upper()}: {dict(sorted(counts.items()))}")
        print(f"  inspect {t_inspect:.1f} s, in-process reads {t_inproc:.1f} s ({len(paths)} files each; the "
              "machine is shared, timings under load)")
    tmp.cleanup()
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
