"""Length units of STEP and IGES files: what a file declares, and the units occsurf writes.

Part of the XCAF side of exchange (:mod:`.xcaf`): :func:`step_unit` reads STEP's ``LENGTH_UNIT``
(``STEPControl_Reader.FileUnits``: SI prefixes and conversion-based units such as ``INCH``) before any
transfer, :func:`iges_unit` the IGES global section's unit flag (and name); :data:`UNITS` and
:func:`unit_scale` give millimetres per unit.
"""

from __future__ import annotations

from typing import Any

from occsurf.algorithms.errors import InvalidGeometryError

from ..messages import one_line

__all__ = ["UNITS", "WRITE_UNITS", "unit_scale", "step_unit", "iges_unit"]

#: Millimetres per unit of each length unit occsurf reports or writes (``ImportedModel.unit``,
#: ``write_step(..., unit=)``, ``occsurf convert --unit``).
UNITS: dict[str, float] = {
    "mm": 1.0, "cm": 10.0, "m": 1000.0, "km": 1e6, "um": 1e-3, "nm": 1e-6, "dm": 100.0,
    "inch": 25.4, "ft": 304.8, "mi": 1609344.0, "mil": 0.0254, "uin": 2.54e-5,
}

#: OCC's unit keyword (``write.step.unit`` / ``write.iges.unit``) of each unit occsurf writes.
_OCC_UNIT = {"mm": "MM", "cm": "CM", "m": "M", "km": "KM", "um": "UM", "inch": "INCH", "ft": "FT",
             "mi": "MI", "mil": "MIL", "uin": "UIN"}

#: The units ``write_step``/``write_iges(..., unit=)`` and ``occsurf convert --unit`` accept.
WRITE_UNITS: tuple[str, ...] = tuple(_OCC_UNIT)

#: STEP unit names (``FileUnits``: SI prefix + 'metre', or a conversion-based unit's name).
_STEP_NAMES = {
    "millimetre": "mm", "millimeter": "mm", "centimetre": "cm", "centimeter": "cm", "metre": "m", "meter": "m",
    "kilometre": "km", "kilometer": "km", "micrometre": "um", "micrometer": "um", "micron": "um",
    "nanometre": "nm", "nanometer": "nm", "decimetre": "dm", "decimeter": "dm",
    "inch": "inch", "in": "inch", "foot": "ft", "feet": "ft", "ft": "ft", "mile": "mi", "mil": "mil",
    "thou": "mil", "microinch": "uin", "mm": "mm", "cm": "cm", "m": "m",
}

#: IGES global-section unit flags (IGES 5.3, §2.2.4.3, parameter 14).
_IGES_FLAGS = {1: "inch", 2: "mm", 4: "ft", 5: "mi", 6: "m", 7: "km", 8: "mil", 9: "um", 10: "cm", 11: "uin"}
_IGES_NAMES = {"IN": "inch", "INCH": "inch", "MM": "mm", "FT": "ft", "MI": "mi", "M": "m", "KM": "km",
               "MIL": "mil", "UM": "um", "MICRON": "um", "CM": "cm", "UIN": "uin"}


def unit_scale(unit: str) -> float:
    """Millimetres per ``unit`` (a key of :data:`UNITS`); raises :class:`InvalidGeometryError` otherwise."""
    if unit not in UNITS:
        raise InvalidGeometryError(f"unit: expected one of {', '.join(UNITS)}, got {unit!r}")
    return UNITS[unit]


def step_unit(reader: Any) -> tuple[str, float, list[str]]:
    """``(unit, millimetres per unit, warnings)`` the STEP file declares (read before any transfer).

    Several representation contexts with different length units: the most frequent is reported, with
    a warning (OCC converts each context's values with its own unit, so the geometry is right).
    """
    from OCP.TColStd import TColStd_SequenceOfAsciiString

    lengths, angles, solid_angles = (TColStd_SequenceOfAsciiString() for _ in range(3))
    try:
        reader.FileUnits(lengths, angles, solid_angles)
    except Exception as err:  # noqa: BLE001 - no unit is not fatal
        return "mm", 1.0, [f"the file's length unit could not be read ({one_line(err)}); millimetres assumed"]
    names = [lengths.Value(i).ToCString() for i in range(1, lengths.Length() + 1)]
    if not names:
        return "mm", 1.0, []
    counts: dict[str, int] = {}
    for n in names:
        counts[n] = counts.get(n, 0) + 1
    name = max(counts, key=lambda n: counts[n])
    warnings = []
    if len(counts) > 1:
        warnings.append(f"the file declares several length units ({', '.join(sorted(counts))}); "
                        f"'{name}' is reported, each part's values are converted with its own")
    unit = _STEP_NAMES.get(name.strip().lower())
    if unit is None:
        factor = _conversion_factor(reader, name)
        if factor is None:
            return name.strip().lower(), 1.0, [*warnings, f"unknown length unit '{name}' (unit_scale 1.0 reported)"]
        return name.strip().lower(), factor, warnings
    return unit, UNITS[unit], warnings


def _conversion_factor(reader: Any, name: str) -> float | None:
    """Millimetres per unit of a STEP ``CONVERSION_BASED_UNIT`` called ``name`` (from the file)."""
    try:
        from OCP.StepBasic import StepBasic_ConversionBasedUnit, StepBasic_SiUnit

        model = reader.WS().Model()
        prefix = {"MILLI": 1.0, "CENTI": 10.0, "DECI": 100.0, "KILO": 1e6, "MICRO": 1e-3, "NANO": 1e-6}
        for k in range(1, model.NbEntities() + 1):
            ent = model.Value(k)
            if isinstance(ent, StepBasic_ConversionBasedUnit) and ent.Name().ToCString() == name:
                factor = ent.ConversionFactor()
                value = float(factor.ValueComponent())
                base = factor.UnitComponent().NamedUnit()
                if isinstance(base, StepBasic_SiUnit):
                    scale = prefix.get(base.Prefix().name.split("_")[-1].upper(), 1000.0) if base.HasPrefix() else 1000.0
                    return value * scale
                return None
    except Exception:  # noqa: BLE001
        return None
    return None


def iges_unit(reader: Any) -> tuple[str, float, list[str]]:
    """``(unit, millimetres per unit, warnings)`` of the IGES global section (flag, else the name)."""
    try:
        header = reader.IGESModel().GlobalSection()
        flag = int(header.UnitFlag())
        name = header.UnitName().ToCString().strip() if header.UnitName() is not None else ""
    except Exception as err:  # noqa: BLE001
        return "mm", 1.0, [f"the file's length unit could not be read ({one_line(err)}); millimetres assumed"]
    unit = _IGES_FLAGS.get(flag) or _IGES_NAMES.get(name.upper())
    if unit is None:
        return "mm", 1.0, [f"unknown IGES unit (flag {flag}, name '{name}'); millimetres assumed"]
    return unit, UNITS[unit], []
