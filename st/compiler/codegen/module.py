"""The whole program: one Python module per ST file, globals, structs, configuration glue."""

from __future__ import annotations

import ast as py

from ...diagnostics import Code
from ...model import types as T
from ..lower import LoweredProgram
from ..syntax import declared
from .expressions import InitGen
from .inline import inlinable
from .pous import BodyGen, FuncGen
from .pyast import Unsupported, _args, _attr, _call, _const, _name, _set_lines, default_value
from .statements import StmtGen, _Typed
from .tests import TestGen


class ModuleGen:
    """Prints the Python modules of a lowered project (compiler/lower)."""

    def __init__(self, program: LoweredProgram, sink, coverage: bool = False, inline_files: frozenset = frozenset()):
        self.p = program.project
        self.blocks = program.blocks
        self.writes = program.writes
        self.initial_orders = program.initial_orders
        self.unbound_in_outs = program.unbound_in_outs
        self.sink = sink
        self.tmp = 0
        self.coverage = coverage
        self.cov_points: list = []  # [(file, line, kind, label, target)]; index = probe id
        self._line_probe: dict = {}
        self.tests_by_file: dict = {}  # path → [FunctionDef]: unit tests, kept apart from the program
        self.inline_candidates: dict = {}  # POUType → its `_body`, if its library allows inlining
        self._inlinable: dict = {}  # POUType → that `_body` if it can be inlined, else None
        # the sources of libraries whose blocks may be inlined; none with TEST blocks, whose MOCK
        # replaces an instance's body at run time
        self.inline_files = inline_files if not self.p.tests else frozenset()

    def inline_body_of(self, pou) -> py.FunctionDef | None:
        """The `_body` of a block that its calls may copy (inline.py), or None."""
        fn = self.inline_candidates.get(pou)  # (None also while the block's class is not generated yet)
        if fn is None:
            return None
        if pou not in self._inlinable:
            self._inlinable[pou] = fn if inlinable(fn) else None
        return self._inlinable[pou]

    def test_modules(self) -> list:
        """[(st file path, Python module)] holding the `_test_<n>` functions (after `generate`)."""
        out = []
        for path, fns in self.tests_by_file.items():
            out.append((path, py.Module(body=fns, type_ignores=[])))
        return out

    def probe(self, file: str, line: int, kind: str, label: str = "", target: int = 0) -> py.stmt:
        """`_cov[k] = 1`: marks a statement line or a branch arm as run (coverage builds only)."""
        if kind == "line":
            k = self._line_probe.get((file, line))
            if k is None:
                k = self._line_probe[(file, line)] = len(self.cov_points)
                self.cov_points.append((file, line, kind, label, target))
        else:
            k = len(self.cov_points)
            self.cov_points.append((file, line, kind, label, target))
        return py.Assign([py.Subscript(_name("_cov"), _const(k), py.Store())], _const(1))

    # ------------------------------------------------------------------ modules
    def generate(self) -> list:
        """Returns [(st file path, Python module AST)] in execution order."""
        by_file: dict[str, list] = {}

        def add(path, node):
            by_file.setdefault(path, []).append(node)

        for _key, t in self.p.types.items():
            if isinstance(t, T.StructType):
                span = t.members and next(iter(t.members.values())).span
                path = span.file if span else "<types>"
                add(path, self.struct_class(t))
        for pou in self.p.pous.values():
            d = declared(pou)
            if d is None or pou.pou_kind == "INTERFACE":
                continue
            node: py.stmt | list[py.stmt]
            self.tmp = 0  # temporaries are local to a POU's functions: numbered per POU
            try:
                if pou.pou_kind == "FUNCTION":
                    node = FuncGen(self, pou).function()
                else:
                    node = BodyGen(self, pou).klass()
            except Unsupported as u:
                self.sink.error(Code.UNSUPPORTED, u.span, u.msg)
                continue
            if isinstance(node, list):
                for n in node:
                    add(d.span.file, n)
            else:
                add(d.span.file, node)
        for test in self.p.tests:
            try:
                self.tests_by_file.setdefault(test.span.file, []).append(TestGen(self, test).function())
            except Unsupported as u:
                self.sink.error(Code.UNSUPPORTED, u.span, u.msg)
        # module-level globals: VAR_GLOBAL and directly addressed variables
        init_stmts = []
        for g in self.p.globals.values():
            gen = InitGen(self)
            val = gen.initial(g.type, g.init)
            init_stmts.append(_set_lines(py.Assign([_name(g.pyname, py.Store())], val), g.span.line if g.span else 1))
        for _addr, (pyname, t) in self.p.direct_vars.items():
            init_stmts.append(_set_lines(py.Assign([_name(pyname, py.Store())], _const(default_value(t))), 1))
        for cfg in self.p.configs:
            for im in cfg.instances:
                if im.args:
                    path = im.span.file if im.span else "<config>"
                    by_file.setdefault(path, []).extend(self.connections(im))
        # globals are initialised last, once every struct and FB class they may instantiate exists
        if init_stmts:
            path = next(iter(self.p.globals.values())).span.file if self.p.globals else "<globals>"
            by_file_list = list(by_file.items()) + [(path, init_stmts)]
        else:
            by_file_list = list(by_file.items())
        modules = []
        for path, body in by_file_list:
            m = py.Module(body=body, type_ignores=[])
            for stmt in body:
                _set_lines(stmt, getattr(stmt, "lineno", None) or 1)
            modules.append((path, m))
        return modules

    def connections(self, im) -> list:
        """A configuration's `PROGRAM inst WITH t : P (in := x, out => y)`: copy-in and copy-out functions."""
        line = im.span.line if im.span else 1
        g_in = StmtGen(self, None)
        g_in.self_name = None
        ins: list[py.stmt] = []
        outs: list[py.stmt] = []
        for p, value, is_out in im.args:
            if not is_out:
                v = g_in.coerce(g_in.expr(value), value, p.type)
                ins.append(py.Assign([_attr(_name("inst"), p.pyname, py.Store())], v))
        g_out = StmtGen(self, None)
        g_out.self_name = None
        for p, value, is_out in im.args:
            if is_out:
                outs.extend(
                    g_out.assign(value, g_out.coerce(_attr(_name("inst"), p.pyname), _Typed(p.type), value.ty), None)
                )
        fns = []
        for name, body, gen in (("_cfg_in_", ins, g_in), ("_cfg_out_", outs, g_out)):
            if body:
                if gen.globals_written:
                    body.insert(0, py.Global(sorted(gen.globals_written)))
                fn = py.FunctionDef(name + im.name.lower(), _args(["inst"]), body, [], None, None)
                fns.append(_set_lines(fn, line))
        return fns

    def struct_class(self, st: T.StructType) -> py.stmt:
        if st.kind == "union":
            return self.union_class(st)
        init = InitGen(self)
        body: list[py.stmt] = []
        for m in st.members.values():
            body.append(
                _set_lines(
                    py.Assign([_attr(_name("self"), m.pyname, py.Store())], init.initial(m.type, m.init)),
                    m.span.line if m.span else 1,
                )
            )
        fn = py.FunctionDef("__init__", _args(["self"]), body or [py.Pass()], [], None, None)
        slots = py.Assign(
            [_name("__slots__", py.Store())], py.Tuple([_const(m.pyname) for m in st.members.values()], py.Load())
        )
        line = next(iter(st.members.values())).span.line if st.members else 1
        cls = py.ClassDef(st.pyname, [_name("_Struct")], [], [slots, fn], [])
        return _set_lines(cls, line)

    def union_class(self, st: T.StructType) -> py.stmt:
        """A UNION: one bytearray, each member a property reading and writing it (runtime.helpers)."""
        # the checker allows only members with a byte image
        members = [(m.pyname, T.byte_layout(m.type) or ("i", 1, False, 1)) for m in st.members.values()]
        size = T.size_of(st)[0]
        line = next(iter(st.members.values())).span.line if st.members else 1
        call = _call("_union_class", _const(st.name), _const(size), _const(tuple(members)))
        return _set_lines(py.Assign([_name(st.pyname, py.Store())], call), line)
