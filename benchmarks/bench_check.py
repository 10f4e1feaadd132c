"""``occsurf check`` against its floor: reading the model and meshing it (issue 28), in one run.

Run from the repository root::

    python benchmarks/bench_check.py [--quick]

Models: the OCCT bearing of ``../shared/realdata`` (213 faces) and a build123d plate with a 19 x 19
grid of filleted, chamfered holes (1089 faces; built by this script into a temporary folder,
never committed). For each model, in the same run:

* **floor**: OCC reads the file (``STEPControl_Reader`` / ``IGESControl_Reader``, ``TransferRoots``) and
  meshes it with ``BRepMesh_IncrementalMesh`` at the report's deflection
  (``tessellation.LINEAR_DEFLECTION`` x the bounding-box diagonal, ``ANGULAR_DEFLECTION``) as the
  report does (``tessellation.mesh_shape``: the planes with Delabella's triangulation, since
  2026-12-06), in a process of its own (time and peak memory): the least any such report can cost.
  OCC's default mesher (one call, Watson's triangulation on the planes too: the floor before) is
  printed beside it;
* ``occsurf check FILE --out DIR`` as a user runs it (a new process, the worker, the page), with
  ``--pictures worst`` (the default), ``none`` and ``all``: wall time, the ratio to the floor, the
  report folder's size and file count, and the peak memory of the command's processes (the
  largest ``ru_maxrss`` among the command and its worker, each run measured under a parent of its
  own: before 2026-12-06 a run reported the largest peak of the runs before it too).

The targets of issue 28 are printed with PASS/FAIL: default <= 4x the floor, ``none`` <= 2x, the
bearing's folder <= 10 MB, memory <= 1 GB on the large model. ``--quick`` leaves out ``all``.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import common  # noqa: E402, F401  (pins BLAS threads before NumPy)

REALDATA = Path(__file__).resolve().parents[2] / "shared" / "realdata"
SCRIPT = Path(sys.executable).with_name("occsurf")


def many_faces_plate(path: Path, n: int = 19) -> int:
    """A 200 x 200 x 12 plate with ``n x n`` through holes, each filleted on top and chamfered below
    (cylinder, torus and cone faces on a plane: 3 n^2 + 6 = 1089 faces for n = 19); returns the face count."""
    from build123d import Box, Cylinder, GeomType, Locations, chamfer, export_step, fillet

    plate = Box(200, 200, 12)
    pitch = 180.0 / n
    pts = [(-90 + pitch * (i + 0.5), -90 + pitch * (j + 0.5)) for i in range(n) for j in range(n)]
    with Locations(*pts):
        holes = Cylinder(3.0, 12)
    part = plate - holes
    circles = [e for e in part.edges() if e.geom_type == GeomType.CIRCLE]
    part = fillet([e for e in circles if abs(e.center().Z - 6) < 1e-6], 1.0)
    circles = [e for e in part.edges() if e.geom_type == GeomType.CIRCLE]
    bottom = [e for e in circles if abs(e.center().Z + 6) < 1e-6]
    part = chamfer(bottom, 0.8)
    export_step(part, str(path))
    return len(part.faces())


def floor_seconds(path: Path, default_mesher: bool = False) -> float:
    """OCC's read and mesh of ``path`` in this process: one ``BRepMesh_IncrementalMesh`` on the
    whole shape with ``default_mesher`` (OCC's default, Watson's triangulation everywhere), else as
    the report meshes (:func:`~occsurf.bridge.rendering.tessellation.mesh_shape`: the planes by
    Delabella, the same nodes)."""
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.IGESControl import IGESControl_Reader
    from OCP.STEPControl import STEPControl_Reader

    from occsurf.bridge.rendering import tessellation

    t0 = time.perf_counter()
    reader = STEPControl_Reader() if path.suffix.lower() in (".step", ".stp") else IGESControl_Reader()
    assert reader.ReadFile(str(path)) == IFSelect_RetDone
    reader.TransferRoots()
    shape = reader.OneShape()
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib

    box = Bnd_Box()
    BRepBndLib.Add_s(shape, box)
    lo, hi = box.CornerMin(), box.CornerMax()
    size = ((hi.X() - lo.X()) ** 2 + (hi.Y() - lo.Y()) ** 2 + (hi.Z() - lo.Z()) ** 2) ** 0.5
    if default_mesher:
        BRepMesh_IncrementalMesh(shape, tessellation.LINEAR_DEFLECTION * size, False, tessellation.ANGULAR_DEFLECTION,
                                 False)
    else:
        tessellation.mesh_shape(shape, tessellation.LINEAR_DEFLECTION * size, tessellation.ANGULAR_DEFLECTION)
    return time.perf_counter() - t0


def floor_run(path: Path, default_mesher: bool) -> tuple[float, float]:
    """:func:`floor_seconds` in a process of its own (best of two there): seconds and that
    process' peak memory (MB)."""
    code = ("import resource, sys; sys.path.insert(0, sys.argv[1]); import bench_check as b; from pathlib import Path; "
            "t = min(b.floor_seconds(Path(sys.argv[2]), sys.argv[3] == '1') for _ in range(2)); "
            "print(t, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)")
    out = subprocess.run([sys.executable, "-c", code, str(Path(__file__).resolve().parent), str(path),
                          "1" if default_mesher else "0"], capture_output=True, text=True, check=True)
    seconds, kb = out.stdout.split()[-2:]
    return float(seconds), float(kb) / 1024.0


#: Runs the command in its arguments, passes its exit status on and prints the peak resident memory
#: (kB) of its process tree (the command and the worker processes it waited for) as the last line.
_PEAK_OF = ("import resource, subprocess, sys; r = subprocess.run(sys.argv[1:], stdout=subprocess.DEVNULL); "
            "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss); sys.exit(r.returncode)")


def run_check(path: Path, out: Path, pictures: str) -> tuple[float, float, int, int]:
    """Wall seconds, worker peak memory (MB), folder bytes and file count of one ``occsurf check``."""
    if out.exists():
        shutil.rmtree(out)
    t0 = time.perf_counter()
    # through a small parent of its own: RUSAGE_CHILDREN's peak is the largest of every child waited
    # for so far, so in this process a run could not report less than the runs before it
    proc = subprocess.run([sys.executable, "-c", _PEAK_OF, str(SCRIPT), "check", str(path), "--out", str(out),
                           "--pictures", pictures], capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if proc.returncode not in (0, 1):
        raise SystemExit(f"occsurf check failed on {path}: {proc.stderr.strip()}")
    peak = float(proc.stdout.strip().splitlines()[-1]) / 1024.0
    files = [f for f in out.rglob("*") if f.is_file()]
    return wall, peak, sum(f.stat().st_size for f in files), len(files)


def main() -> int:
    quick = "--quick" in sys.argv
    tmp = Path(tempfile.mkdtemp(prefix="bench_check_"))
    try:
        models = []
        bearing = REALDATA / "occt__bearing.iges"
        if bearing.exists():
            models.append(("OCCT bearing (213 faces)", bearing))
        plate = tmp / "plate.step"
        n_faces = many_faces_plate(plate)
        models.append((f"build123d plate ({n_faces} faces)", plate))
        print(f"machine: {common.machine_note()}; load average {os.getloadavg()[0]:.2f}")
        ok = True
        for label, path in models:
            floor, floor_peak = floor_run(path, False)
            watson, watson_peak = floor_run(path, True)
            print(f"\n{label}: floor (OCC read + mesh as the report meshes, in a process) {floor:.2f} s, peak "
                  f"{floor_peak:.0f} MB; OCC's default mesher (Watson on the planes too) {watson:.2f} s, peak "
                  f"{watson_peak:.0f} MB")
            for pictures in ("worst", "none") + (() if quick else ("all",)):
                wall, peak, size, count = run_check(path, tmp / f"out_{pictures}", pictures)
                ratio = wall / floor
                print(f"  occsurf check --pictures {pictures:5s}: {wall:6.2f} s ({ratio:5.1f}x the floor), "
                      f"{size / 2**20:6.1f} MB in {count} files, worker peak {peak:.0f} MB")
                if pictures == "worst":
                    ok &= ratio <= 4.0
                    print(f"    target default <= 4x: {'PASS' if ratio <= 4.0 else 'FAIL'}")
                    if "bearing" in label:
                        print(f"    target folder <= 10 MB: {'PASS' if size <= 10 * 2**20 else 'FAIL'}")
                    else:
                        print(f"    target memory <= 1 GB: {'PASS' if peak <= 1024 else 'FAIL'}")
                if pictures == "none":
                    ok &= ratio <= 2.0
                    print(f"    target --pictures none <= 2x: {'PASS' if ratio <= 2.0 else 'FAIL'}")
        return 0 if ok else 1
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
