"""The README section "From build123d / cadquery" (issue 16) runs as written.

The section is kept here verbatim until the lead merges it into README.md (where
``tests/test_readme.py`` then runs it with the others); this test runs its ```python blocks in one
namespace in a scratch directory, as that test does, and checks what they print.
"""

from __future__ import annotations

import contextlib
import io
import re

import pytest

pytest.importorskip("build123d")
pytest.importorskip("cadquery")

SECTION = '''
## From build123d / cadquery

Files come back as the objects build123d and cadquery users already hold, and every bridge function
that takes faces or a model takes those objects: Faces, Shells, Solids, Compounds, a cadquery
`Workplane` or `Assembly`, a build123d builder.

```python
import build123d as bd
from occsurf.bridge import fill_model, inspect_model, read_step, write_step

plate = bd.Box(10, 20, 2) - bd.Cylinder(2, 2)            # a plate with a hole
plate_a = plate.moved(bd.Location((0, 0, 0)))
plate_a.label, plate_a.color = "plate_a", bd.Color("red")
plate_b = plate.moved(bd.Location((30, 0, 0)))            # a second instance of the same part
plate_b.label, plate_b.color = "plate_b", bd.Color("blue")
bd.export_step(bd.Compound(label="plates", children=[plate_a, plate_b]), "plates.step")

plates = read_step("plates.step", as_="build123d")        # a Compound tree: labels, colours, placements
print([(c.label, tuple(c.color)) for c in plates.children])
# [('plate_a', (1.0, 0.0, 0.0, 1.0)), ('plate_b', (0.0, 0.0, 1.0, 1.0))]
plates_cq = read_step("plates.step", as_="cadquery")      # a cadquery Assembly: names, colours, locations
print([(c.name, c.loc.toTuple()[0]) for c in plates_cq.children])
# [('plate_a', (0.0, 0.0, 0.0)), ('plate_b', (30.0, 0.0, 0.0))]
write_step("plates_17.step", plates_cq)                   # written back: structure, names, colours, 17 digits
print([n.name for n in read_step("plates_17.step").assembly.children])   # ['plate_a', 'plate_b']
```

```python
print(sorted({r.surface_type for r in inspect_model(plate_a, samples=5)}))  # ['Cylinder', 'Plane']
faces = [bd.Sphere(5).faces()[0]]
for plane in (bd.Plane.XZ, bd.Plane.YZ, bd.Plane.XY.offset(3)):     # cut the sphere into 8 faces
    faces = [g for f in faces for half in f.split(plane, keep=bd.Keep.BOTH) for g in half.faces()]
open_ball = bd.Shell([f for f in faces if f.center().Z < 3])       # the 4 faces above z = 3 removed
ball = fill_model(open_ball, compare_occ=False, as_="build123d")   # the 4-sided hole filled, G1
print(type(ball.shape).__name__, ball.holes[0].status, ball.shape.is_valid, f"{ball.holes[0].g1:.0e}")
# Solid filled True 3e-10      (the largest G1 angle along the hole, degrees, measured by OCC)
```

Instances stay references to one part (`plates.children[0].wrapped.IsPartner(plates.children[1].wrapped)`),
named after the instance (build123d 0.12's own `import_step` names both `plate_b`, after the part).
`write_step` / `write_iges` take a build123d tree or a cadquery Assembly with its structure
(`model_from_object(obj)` gives the `ImportedModel`; IGES has no instances: placed copies, names and
colours kept).
A build123d shape has one colour: a part whose faces have several keeps its largest face's colour in
build123d, and each face's in cadquery (`addSubshape`). OCC's message printers keep the level you set:
the bridge quiets OCC's banners during its own calls only (`occsurf.bridge.quiet_messages`);
`occsurf.bridge.silence_messages()` quiets them for the whole process.
'''

BLOCK = re.compile(r"^```python\n(.*?)^```", re.S | re.M)


def test_section_blocks_run(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    namespace: dict[str, object] = {"__name__": "readme"}
    out = io.StringIO()
    blocks = BLOCK.findall(SECTION)
    assert len(blocks) == 2
    with contextlib.redirect_stdout(out):
        for source in blocks:
            exec(compile(source, "README section", "exec"), namespace)  # noqa: S102 - ours
    lines = out.getvalue().splitlines()
    assert lines[0] == "[('plate_a', (1.0, 0.0, 0.0, 1.0)), ('plate_b', (0.0, 0.0, 1.0, 1.0))]"
    assert lines[1] == "[('plate_a', (0.0, 0.0, 0.0)), ('plate_b', (30.0, 0.0, 0.0))]"
    assert lines[2] == "['plate_a', 'plate_b']"
    assert lines[3] == "['Cylinder', 'Plane']"
    kind, status, valid, g1 = lines[4].split()
    assert (kind, status, valid) == ("Solid", "filled", "True") and float(g1) < 1e-6
    assert (tmp_path / "plates.step").is_file()
