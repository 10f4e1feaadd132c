"""IGES pointer cycles are refused before OCC reads them (found by the mutation fuzz, CI of 2026-12-05).

One swapped pointer of a filleted box's IGES file (``tests/bridge/test_fuzz_exchange.py``: ``swap``
13, 262145) made the trimmed surface 144 at D3 point to itself as its base surface: OCC's transfer
recursed round it until the reading process died of SIGSEGV, in-process (the fuzz's worker) as in
the CLI's worker. :func:`occsurf.bridge.exchange.iges_checks.scan_iges` now follows the pointer fields of
the entities a reader builds recursively (the IGES 5.3 schema of 102, 118, 120, 122, 140-144, 510)
and refuses a cycle through them in one line; the real files read as before.

A surface of revolution (120) whose axis is not a line (110) killed OCC's reader too (``swap`` 1,
8194 made the box's fillet's axis pointer 10, the second line of a directory entry; a composite
curve or no entry did the same): refused in one line as well.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from occsurf.algorithms.errors import ExchangeError
from occsurf.bridge.exchange.step_iges import READ_JOB, READ_PRELOAD, read_iges, write_iges
from occsurf.bridge.isolation import CRASHED, run_jobs

REPO = Path(__file__).resolve().parents[2]
REALDATA = REPO.parent / "shared" / "realdata"


@pytest.fixture(scope="module")
def box(tmp_path_factory) -> bytes:
    import cadquery as cq

    shape = cq.Workplane().box(1, 2, 3).edges("|Z").fillet(0.2).val().wrapped
    return write_iges(tmp_path_factory.mktemp("iges-box") / "box.igs", [shape]).read_bytes()


def _edited(box: bytes, old: bytes, new: bytes, path: Path) -> Path:
    assert box.count(old) == 1 and len(old) == len(new)  # the writer's numbering, checked
    path.write_bytes(box.replace(old, new))
    return path


def _refused_by_every_reader(bad: Path, match: str, said: str) -> None:
    """``bad`` refused by ``read_iges`` (the message matching ``match``), read without a crash by the
    isolated read job (it died of SIGSEGV before the checks), and refused by ``occsurf inspect`` in
    one line saying ``said``, exit 2, no traceback."""
    with pytest.raises(ExchangeError, match=match):
        read_iges(bad)
    (out,) = run_jobs(READ_JOB, [{"path": str(bad), "format": "iges", "out": str(bad) + ".brep"}], timeout=120,
                      preload=READ_PRELOAD)
    assert out.status != CRASHED, out.exit_reason
    proc = subprocess.run([sys.executable, "-m", "occsurf.bridge.cli", "inspect", str(bad)], capture_output=True,
                          text=True, cwd=REPO, timeout=300)
    assert proc.returncode == 2 and said in proc.stderr and "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1


def test_a_trimmed_surface_pointing_to_itself_is_refused_not_a_crash(box: bytes, tmp_path: Path) -> None:
    bad = _edited(box, b"144,5,1,0,7;", b"144,3,1,0,7;", tmp_path / "self.igs")
    _refused_by_every_reader(bad, r"damaged IGES file \(directory entry D3, type 144, points to itself\)",
                             "points to itself")


def test_a_cycle_of_two_pointers_is_refused(box: bytes, tmp_path: Path) -> None:
    """The trimmed surface's outer boundary (142 at D7) given the trimmed surface as its surface:
    D3 -> D7 -> D3."""
    bad = _edited(box, b"142,0,5,0,9,2;", b"142,0,3,0,9,2;", tmp_path / "cycle.igs")
    with pytest.raises(ExchangeError, match=r"a cycle of pointers through 2 entities: D3 type 144, D7 type 142"):
        read_iges(bad)


def test_the_clean_box_and_the_real_files_read_as_before(box: bytes, tmp_path: Path) -> None:
    clean = tmp_path / "box.igs"
    clean.write_bytes(box)
    assert len(read_iges(clean).faces) == 10
    assert len(read_iges(REPO / "step_samples" / "mixed.igs").faces) > 0
    if not REALDATA.is_dir():
        pytest.skip(f"{REALDATA} is absent: the real IGES files are checked where ../shared is beside the repository")
    for name, faces in (("occt__bearing.iges", 213), ("pythonocc-core__sunglasses_lens.igs", 9)):
        model = read_iges(REALDATA / name)
        assert len(model.faces) == faces and not model.warnings


@pytest.mark.parametrize("axis, said", [(b"9,", "D9, of type 102"), (b"58", "D58, not the start of a directory entry"),
                                        (b"0,", "none")])
def test_a_surface_of_revolution_without_a_line_for_its_axis_is_refused_not_a_crash(box: bytes, tmp_path: Path,
                                                                                    axis: bytes, said: str) -> None:
    old = b"120,57,59,4.71238898,6.283185307;"
    new = b"120," + axis + (b"59,4.71238898,6.283185307;" if axis.endswith(b",") else b",59,4.71238898,6.283185307;")
    new = new.ljust(len(old))
    bad = _edited(box, old, new, tmp_path / "axis.igs")
    _refused_by_every_reader(bad, rf"surface of revolution 120 at D53: its axis is {said}; it must be a line",
                             "it must be a line")
