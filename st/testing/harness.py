"""Python-side testing of ST: a PLC with helpers to drive inputs and step virtual time,
and handles to call a single FUNCTION_BLOCK or FUNCTION from Python.

    p = TestPLC.from_files("programs/traffic_light.st")
    p.pulse("main.start")                      # TRUE for one scan, then FALSE
    p.run_until("main.green", timeout="5s")    # scans until TRUE; the PLC time it took
    ton = p.fb("TON"); ton(IN=True, PT="100ms"); p.advance("100ms"); ton(IN=True); assert ton.Q
"""

from __future__ import annotations

from collections.abc import Callable

from ..compiler.codegen.pyast import default_value
from ..facade import PLC
from ..model import types as T
from ..runtime.values import from_python, parse_duration_arg, to_python


class TestPLC(PLC):
    """A PLC with test helpers. Time is virtual: nothing here sleeps."""

    __test__ = False  # not a pytest test class

    def set(self, values: dict | None = None, **kw) -> TestPLC:
        """Write several variables: p.set({"main.start": True, "main.speed": 3})."""
        for path, v in {**(values or {}), **kw}.items():
            self[path] = v
        return self

    def pulse(self, path: str, width=None, value=True) -> TestPLC:
        """Hold `path` at `value` for `width` of PLC time (default: one base tick), then restore it."""
        old = self[path]
        self[path] = value
        if width is None:
            self.scan()
        else:
            self.advance(max(parse_duration_arg(width), self.tick))
        self[path] = old
        return self

    def run_until(self, condition: str | Callable, timeout="10s") -> int:
        """Scan until `condition` (a BOOL variable path, or a callable taking the PLC) holds.
        Returns the PLC time it took (ns); AssertionError when `timeout` of PLC time passes first."""
        test = (lambda p: bool(p[condition])) if isinstance(condition, str) else condition
        start = self.time
        end = start + parse_duration_arg(timeout)
        while not test(self):
            if self.time >= end:
                what = condition if isinstance(condition, str) else getattr(condition, "__name__", "condition")
                raise AssertionError(
                    f"{what} did not become true within {parse_duration_arg(timeout) / 1e9:g} s of PLC time"
                )
            self.scan()
        return self.time - start

    def trace(self, paths: list, duration) -> list:
        """Run for `duration` and record the variables after every scan: [(time ns, {path: value})]."""
        out = []
        end = self.time + parse_duration_arg(duration)
        while self.time < end:
            self.scan()
            out.append((self.time, {p: self[p] for p in paths}))
        return out

    def fb(self, type_name: str) -> FBHandle:
        """A fresh instance of a FUNCTION_BLOCK (or PROGRAM) type, driven from Python."""
        pou = self.project.pous.get(type_name.lower())
        if pou is None or pou.pou_kind not in ("FUNCTION_BLOCK", "PROGRAM"):
            raise KeyError(f"no FUNCTION_BLOCK or PROGRAM named '{type_name}'")
        return FBHandle(self, pou, self.ns[pou.pyname]())

    def function(self, name: str) -> Callable:
        """An ST FUNCTION as a Python callable: f(1, 2) or f(IN1=1, IN2=2) → its result."""
        pou = self.project.pous.get(name.lower())
        if pou is None or pou.pou_kind != "FUNCTION" or pou.decl is None:
            raise KeyError(f"no FUNCTION written in ST named '{name}'")
        fn = self.ns[pou.pyname]
        inputs = pou.inputs()

        def call(*args, **kw):
            if len(args) > len(inputs):
                raise TypeError(f"{pou.name} takes {len(inputs)} inputs")
            given = {p.name.lower(): v for p, v in zip(inputs, args)}
            given.update({k.lower(): v for k, v in kw.items()})
            unknown = set(given) - {p.name.lower() for p in inputs}
            if unknown:
                raise TypeError(f"{pou.name} has no input {', '.join(sorted(unknown))}")
            pyargs = []
            for p in pou.params():
                if p.section == "VAR_INPUT":
                    pyargs.append(
                        from_python(given[p.name.lower()], p.type, f"{pou.name}.{p.name}")
                        if p.name.lower() in given
                        else _initial(self, p)
                    )
                elif p.section == "VAR_IN_OUT":
                    raise TypeError(f"{pou.name} has VAR_IN_OUT parameters; call it from ST")
                else:
                    pyargs.append(None)
            result = fn(*pyargs)
            return to_python(result, pou.return_type) if pou.return_type is not None else None

        return call


def _initial(plc: PLC, p: T.VarSym):
    """An omitted input: its declared initial value when that is a literal, else the type's default."""
    if p.init is not None and hasattr(p.init, "value"):
        return from_python(p.init.value, p.type)
    return default_value(p.type)


class FBHandle:
    """One FB instance: `h(IN=True, PT="100ms")` writes inputs and runs one call; `h.Q` reads a variable."""

    def __init__(self, plc: PLC, pou: T.POUType, obj):
        object.__setattr__(self, "_plc", plc)
        object.__setattr__(self, "_pou", pou)
        object.__setattr__(self, "_obj", obj)

    def __call__(self, **inputs) -> FBHandle:
        for name, v in inputs.items():
            setattr(self, name, v)
        self._plc.ns["_now"] = self._plc.time
        self._obj._body()
        return self

    def _sym(self, name: str) -> T.VarSym:
        sym = self._pou.vars.get(name.lower())
        if sym is None or sym.section in ("VAR_EXTERNAL", "VAR_TEMP"):
            raise AttributeError(f"{self._pou.name} has no variable '{name}'")
        return sym

    def __getattr__(self, name: str):
        if name.startswith("_"):
            raise AttributeError(name)
        sym = self._sym(name)
        return to_python(getattr(self._obj, sym.pyname), sym.type)

    def __setattr__(self, name: str, value) -> None:
        sym = self._sym(name)
        setattr(self._obj, sym.pyname, from_python(value, sym.type, f"{self._pou.name}.{name}"))

    def __repr__(self) -> str:
        return f"<{self._pou.name} instance>"
