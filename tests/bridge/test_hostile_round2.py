"""Issue 34: hostile input, round 2. Each test here failed on the code before it (a traceback, a bare
Python error, a silent NaN or a run that went on without its timeout)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from occsurf.algorithms import BSplineCurve, BSplineSurface, tolerances
from occsurf.algorithms.errors import (
    ArgumentTypeError,
    InvalidGeometryError,
    OccsurfError,
    ParameterError,
    UnknownNameError,
)
from occsurf.bridge import cli
from occsurf.bridge.isolation import MAX_TIMEOUT, run_jobs
from occsurf.bridge.messages import strip_path

REPO = Path(__file__).resolve().parents[2]
DOME = REPO / "step_samples" / "holes" / "dome_holes.step"
posix = pytest.mark.skipif(os.name != "posix", reason="POSIX symbolic links")


def _main(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = cli.main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


# ------------------------------------------------------------------------ item 4: --timeout 1e308
@pytest.mark.parametrize("command", [
    ["fill", str(DOME), "--out", "o.step"],
    ["inspect", str(DOME)],
    ["convert", str(DOME), "o.igs"],
    ["check", str(DOME)],
    ["audit", str(DOME), "--out", "audit_out"],
    ["render", str(DOME), "--out", "o.png", "--preset", "studio"],
])
@pytest.mark.parametrize("value", ["1e308", "1e7"])
def test_timeout_beyond_the_maximum_is_one_line_exit_2(capsys: pytest.CaptureFixture[str], tmp_path: Path,
                                                       monkeypatch: pytest.MonkeyPatch, command: list[str],
                                                       value: str) -> None:
    """1e308 once killed the watchdog thread with an OverflowError and the run went on unguarded."""
    monkeypatch.chdir(tmp_path)
    code, out, err = _main(capsys, *command, "--timeout", value)
    assert code == 2 and out == ""
    assert err == f"occsurf: {command[0]}: argument --timeout: at most {MAX_TIMEOUT:g} seconds, got '{value}'\n"
    assert list(tmp_path.iterdir()) == []


def test_run_jobs_refuses_a_timeout_beyond_the_maximum() -> None:
    with pytest.raises(ValueError, match="timeout: at most 1e\\+06 seconds"):
        run_jobs("json:dumps", [1], timeout=1e308)
    assert [o.value for o in run_jobs("json:dumps", [1], timeout=MAX_TIMEOUT, isolate=False)] == ["1"]


# ------------------------------------------------------------------------ item 5: a loop of symlinks
@posix
@pytest.mark.parametrize("command", [
    ["fill", "{loop}", "--out", "o.step"],
    ["render", "{loop}", "--out", "o.png", "--preset", "studio"],
    ["fit", "{loop}", "--tol", "0.1", "--out", "o.step"],
    ["inspect", "{loop}"],
    ["convert", "{loop}", "o.igs"],
])
def test_a_loop_of_symbolic_links_is_one_line_exit_2(capsys: pytest.CaptureFixture[str], tmp_path: Path,
                                                     monkeypatch: pytest.MonkeyPatch, command: list[str]) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "a.step").symlink_to("b.step")
    (tmp_path / "b.step").symlink_to("a.step")
    code, out, err = _main(capsys, *[c.format(loop="a.step") for c in command])
    assert code == 2 and "Traceback" not in err and "RuntimeError" not in err
    assert "a.step: " in err and "a loop of symbolic links" in err
    assert not any(p.name.startswith("o.") for p in tmp_path.iterdir())


@posix
def test_strip_path_survives_a_loop_of_symbolic_links(tmp_path: Path) -> None:
    (tmp_path / "a.step").symlink_to("b.step")
    (tmp_path / "b.step").symlink_to("a.step")
    loop = tmp_path / "a.step"
    assert strip_path(f"{loop}: a loop of symbolic links", loop) == "a loop of symbolic links"


def test_fill_refuses_a_device_before_starting_a_worker(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    if not Path("/dev/zero").exists():
        pytest.skip("no /dev/zero")
    code, out, err = _main(capsys, "fill", "/dev/zero", "--out", str(tmp_path / "o.step"))
    assert code == 2 and err == "occsurf: /dev/zero: is a character device, not a STEP or IGES file; not read\n"


# ------------------------------------------------------------------------ item 9: domains narrower than the knot tolerance
def _cubic() -> BSplineCurve:
    return BSplineCurve(3, [0, 0, 0, 0, 1, 1, 1, 1], [[0, 0, 0], [1, 1, 0], [2, -1, 0], [3, 0, 0]])


@pytest.mark.parametrize("end", [1e-320, 1e-200, 1e-12])
def test_reparametrize_to_a_domain_within_the_knot_tolerance_is_refused(end: float) -> None:
    """(0, 1e-320) was accepted and evaluated to NaN with a RuntimeWarning only."""
    with pytest.raises(ParameterError, match="no longer than the knot tolerance"):
        _cubic().reparametrize(0.0, end)
    s = BSplineSurface((1, 1), ([0, 0, 1, 1], [0, 0, 1, 1]), np.arange(12.0).reshape(2, 2, 3))
    with pytest.raises(ParameterError, match=r"reparametrize \(v\).*no longer than the knot tolerance"):
        s.reparametrize((0, 1), (0.0, end))
    ok = _cubic().reparametrize(0.0, 1e-11)  # just above the tolerance: finite values
    assert np.all(np.isfinite(ok.derivatives(np.array([0.0, 5e-12, 1e-11]), 1)[:, 0]))


def test_a_knot_vector_whose_domain_is_within_the_knot_tolerance_is_refused() -> None:
    with pytest.raises(InvalidGeometryError, match=r"the domain \[0.0, 1e-320\] is 1e-320 long"):
        BSplineCurve(3, [0, 0, 0, 0, 1e-320, 1e-320, 1e-320, 1e-320], _cubic().control_points)


# ------------------------------------------------------------------------ item 10: bare Python errors
def test_unknown_tolerance_is_an_occsurf_error_and_still_a_key_error() -> None:
    with pytest.raises(UnknownNameError) as info, tolerances.override(NOPE=1.0):
        pass
    assert isinstance(info.value, OccsurfError) and isinstance(info.value, KeyError)
    assert str(info.value).startswith("override: 'NOPE' is not a tolerance; known: ")  # not quoted as KeyError does
    with pytest.raises(ArgumentTypeError, match="must be a real number") as info2, \
            tolerances.override(KNOT_REMOVAL="small"):  # type: ignore[arg-type]
        pass
    assert isinstance(info2.value, TypeError)


def test_from_occ_of_an_empty_handle_is_invalid_geometry() -> None:
    """A wrapper that holds no OCC object (made by ``__new__``): its arrays read as None. Run in a
    child process: calls on such a wrapper are undefined behaviour in OCC."""
    code = (
        "from OCP.Geom import Geom_BSplineCurve, Geom_BSplineSurface\n"
        "from occsurf.algorithms.errors import InvalidGeometryError\n"
        "from occsurf.bridge.conversion.splines import from_occ\n"
        "for cls in (Geom_BSplineSurface, Geom_BSplineCurve):\n"
        "    try:\n"
        "        from_occ(cls.__new__(cls))\n"
        "    except InvalidGeometryError as err:\n"
        "        print(err)\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.splitlines() == [
        f"from_occ: the {name} holds no geometry (a null or uninitialised handle: its poles read as None)"
        for name in ("Geom_BSplineSurface", "Geom_BSplineCurve")]


@pytest.mark.parametrize("isolated", [False, True])
def test_bytes_paths_are_read(isolated: bool) -> None:
    """``read_step(b"/path/part.stp")``: bytes are an OS path as the system gives it."""
    from occsurf.bridge.exchange.step_iges import read_step

    model = read_step(os.fsencode(DOME), isolated=isolated)
    assert len(model.faces) == 18
