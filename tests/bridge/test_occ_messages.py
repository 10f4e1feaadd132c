"""OCC's message level: bridge calls keep translator banners off stdout and leave every printer at the
level its owner set (issue 16, process hygiene). Before, the first bridge import lowered the default
printers to ``Message_Fail`` for the whole process and never restored them.

Control: OCC's IGES reader prints ``Total number of loaded entities`` at ``Message_Info`` (the
default level); the subprocess test shows it does so on the same file, so the "nothing printed"
assertion can fail.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
import threading
from pathlib import Path

import pytest
from OCP.Message import Message, Message_Gravity

from occsurf.algorithms.errors import ExchangeError
from occsurf.bridge import _occ

SAMPLES = Path(__file__).resolve().parents[2] / "step_samples"
IGES = SAMPLES / "mixed.igs"
BANNER = "Total number of loaded entities"


@pytest.fixture
def printer():
    """The default printer, its level restored after the test whatever the test does."""
    p = Message.DefaultMessenger_s().Printers().First()
    old = p.GetTraceLevel()
    yield p
    p.SetTraceLevel(old)


def _bridge_calls(tmp_path: Path) -> None:
    from occsurf.bridge import fill_model, from_occ, inspect_model, read_iges, read_step, write_iges, write_step

    model = read_iges(IGES)
    write_step(tmp_path / "m.step", [f.surface for f in model.faces if f.surface is not None][:3])
    write_iges(tmp_path / "m.igs", model.faces[0].surface)
    read_step(tmp_path / "m.step")
    inspect_model(model, samples=3)
    from_occ(model.faces[0].face)
    fill_model(model.faces[0].face, compare_occ=False)


@pytest.mark.slow
@pytest.mark.parametrize("level", [Message_Gravity.Message_Trace, Message_Gravity.Message_Info,
                                   Message_Gravity.Message_Warning, Message_Gravity.Message_Fail])
def test_user_printer_level_is_unchanged_after_bridge_calls(printer, level, tmp_path):
    printer.SetTraceLevel(level)
    _bridge_calls(tmp_path)
    assert printer.GetTraceLevel() == level


def test_level_restored_when_the_call_fails(printer, tmp_path):
    printer.SetTraceLevel(Message_Gravity.Message_Trace)
    bad = tmp_path / "bad.step"
    bad.write_text("ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\n#1=FOO(;\nENDSEC;\nEND-ISO-10303-21;\n")
    from occsurf.bridge import read_step

    with pytest.raises(ExchangeError):
        read_step(bad)
    assert printer.GetTraceLevel() == Message_Gravity.Message_Trace


def test_quiet_messages_nests_and_survives_threads(printer):
    from occsurf.bridge import read_iges

    printer.SetTraceLevel(Message_Gravity.Message_Trace)
    with _occ.quiet_messages():
        assert printer.GetTraceLevel() == Message_Gravity.Message_Fail
        with _occ.quiet_messages():
            pass
        assert printer.GetTraceLevel() == Message_Gravity.Message_Fail  # the inner block restored nothing
    assert printer.GetTraceLevel() == Message_Gravity.Message_Trace
    errors: list[BaseException] = []

    def read() -> None:
        try:
            for _ in range(2):
                read_iges(IGES)
        except BaseException as err:  # noqa: BLE001 - reported below
            errors.append(err)

    threads = [threading.Thread(target=read) for _ in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    assert printer.GetTraceLevel() == Message_Gravity.Message_Trace


def test_fresh_process_keeps_default_level_and_prints_no_banner():
    """In a new interpreter: importing every bridge room and reading an IGES file prints nothing on
    stdout and leaves the default level (Message_Info); OCC's own reader, after that, prints its banner."""
    script = textwrap.dedent(f"""
        import importlib, pkgutil
        from OCP.Message import Message
        level = lambda: Message.DefaultMessenger_s().Printers().First().GetTraceLevel().name
        import occsurf.bridge as bridge
        for info in pkgutil.walk_packages(bridge.__path__, "occsurf.bridge."):
            if ".cli" not in info.name and ".audit" not in info.name:
                importlib.import_module(info.name)
        print("after imports", level(), flush=True)
        bridge.read_iges({str(IGES)!r})
        print("after read", level(), flush=True)
        from OCP.IGESControl import IGESControl_Reader
        r = IGESControl_Reader(); r.ReadFile({str(IGES)!r}); r.TransferRoots()
    """)
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert lines[0] == "after imports Message_Info" and lines[1] == "after read Message_Info", out.stdout
    assert BANNER not in "\n".join(lines[:2])
    assert BANNER in "\n".join(lines[2:])  # the control: OCC prints it at this level


def test_silence_messages_is_the_explicit_process_wide_option(printer):
    from occsurf.bridge import silence_messages

    printer.SetTraceLevel(Message_Gravity.Message_Info)
    silence_messages()
    assert printer.GetTraceLevel() == Message_Gravity.Message_Fail
