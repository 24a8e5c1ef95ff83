"""PLCopen Motion Control Part 1 (v2.0): MC_* function blocks, the axis state machine, profiles.

The blocks are declared in `plcopen.st` and run natively (`fbs.py`); each axis (`axis.py`) keeps
its state, command ledger and buffer and is advanced by the kernel after its task's job.
"""

from __future__ import annotations

from pathlib import Path

from ...compiler.library import Library
from .axis import Axis, AxisConfig, AxisView
from .errors import E
from .fbs import install

SOURCE_PATH = Path(__file__).with_name("plcopen.st")


def library() -> Library:
    lib = Library(
        "plcopen", sources=[(str(SOURCE_PATH), SOURCE_PATH.read_text())], version="1", yields_to_own_types=True
    )
    lib.helpers["_post_exec_plcopen"] = install
    return lib


def registry(plc):
    """The PLC's MotionRegistry (None when the program uses no MC_* block)."""
    return plc.ns.get("_motion")


def axis_of(plc, path: str) -> Axis:
    """The Axis behind an AXIS_REF variable, e.g. axis_of(plc, "main.axis1")."""
    reg = registry(plc)
    if reg is None:
        raise KeyError("the program uses no PLCopen motion block")
    return reg.axis(plc.ref(path).get())


def axis_view(plc, name: str | int) -> AxisView:
    """An axis as the blocks saw it in the last scan (AxisView), by its configured name ("x"), its
    AxisNo, or the path of an AXIS_REF variable ("main.a1"); `plc.axis(name)` calls this."""
    reg = registry(plc)
    if reg is None:
        raise KeyError("the program uses no PLCopen motion block")
    ax = None
    if isinstance(name, int):
        ax = next((a for a in reg.axes.values() if a.axis_no == name), None)
    else:
        ax = next((a for a in reg.axes.values() if a.cfg.name == name), None)
        if ax is None:
            try:
                ax = reg.axis(plc.ref(name).get())
            except KeyError:
                ax = None
    if ax is None:
        known = ", ".join(sorted(a.cfg.name for a in reg.axes.values())) or "none in use yet"
        raise KeyError(f"no axis {name!r} (axes: {known})")
    return ax.last_view or ax.view()


def configure_axes(plc, axes) -> None:
    """Axis configurations by AxisNo: a dict {no: {field: value}} or {no: AxisConfig}, or the path
    of a TOML file with [[axis]] tables (no = 1, modulo = 360.0, max_velocity = …; see AxisConfig).
    Axes already in use get the new configuration at once."""
    reg = registry(plc)
    if reg is None:
        raise KeyError("the program uses no PLCopen motion block")
    where = ""
    if isinstance(axes, (str, Path)):
        where = f"{axes}: "
        axes = load_axes(str(axes))
    for no, cfg in axes.items():
        if not isinstance(cfg, AxisConfig):
            cfg = _axis_config(no, dict(cfg), where or "configure_axes: ")
        if cfg.homing not in ("current", "switch"):
            raise ValueError(f"{where}axis {no}: homing must be 'current' or 'switch', not {cfg.homing!r}")
        if cfg.set_position_in_motion not in ("keep_target", "keep_trajectory"):
            raise ValueError(
                f"{where}axis {no}: set_position_in_motion must be 'keep_target' or 'keep_trajectory', "
                f"not {cfg.set_position_in_motion!r}"
            )
        reg.configs[int(no)] = cfg
        reg.signals.pop(int(no), None)
        if cfg.home_switch:
            reg.signals[int(no)] = _switch_reader(plc, cfg.home_switch, f"{where}axis {no}")
    for ax in reg.axes.values():
        no = getattr(ax, "axis_no", None)
        if no in reg.configs:
            ax.cfg = reg.configs[no]
            ax.home_signal = reg.signals.get(no)


def _switch_reader(plc, path: str, what: str):
    """A callable reading the BOOL variable `path` (the reference switch of an axis); resolved on
    every read, which only happens while homing, so it survives an online change."""
    try:
        plc.ref(path)
    except KeyError:
        raise ValueError(f"{what}: home_switch '{path}' is not a variable of the program") from None
    return lambda: bool(plc[path])


def load_axes(path: str) -> dict:
    """[[axis]] tables of a TOML file → {AxisNo: AxisConfig}; errors name the file and the entry."""
    import tomllib

    try:
        with open(path, "rb") as f:
            doc = tomllib.load(f)
    except OSError as e:
        raise ValueError(f"{path}: cannot read the axis configuration: {e.strerror}") from None
    except tomllib.TOMLDecodeError as e:
        raise ValueError(f"{path}: {e}") from None
    out = {}
    for i, item in enumerate(doc.get("axis", []), 1):
        item = dict(item)
        no = item.pop("no", None)
        if not isinstance(no, int) or no <= 0:
            raise ValueError(f"{path}: axis entry {i}: needs no = <AxisNo>, a positive integer")
        out[no] = _axis_config(no, item, f"{path}: ")
    return out


def _axis_config(no, item: dict, where: str) -> AxisConfig:
    """One axis's settings → AxisConfig; an unknown setting is an error that names where it is."""
    import dataclasses

    fields = {f.name for f in dataclasses.fields(AxisConfig)}
    unknown = set(item) - fields
    if unknown:
        raise ValueError(
            f"{where}axis {no}: unknown setting '{sorted(unknown)[0]}' (known: {', '.join(sorted(fields))})"
        )
    return AxisConfig(**{"name": f"axis{no}", **item})


__all__ = [
    "Axis",
    "AxisConfig",
    "AxisView",
    "E",
    "library",
    "registry",
    "axis_of",
    "axis_view",
    "configure_axes",
    "load_axes",
]
