"""Configurations, recursion and self-containment checks, unused-variable warnings."""
from __future__ import annotations


from ...source import Span
from .. import ast as A
from ...model import types as T
from ...model.program import ConfigModel, InstanceModel, TaskModel
from .common import _SECTIONS_PARAM, Scope


class ConfigurationMixin:
    # ================================================================ configuration
    def _check_configuration(self, cfg: A.Configuration) -> None:
        cm = ConfigModel(cfg.name)
        scope = Scope(None, {})
        for res in cfg.resources:
            for td in res.tasks:
                tm = TaskModel(td.name, span=td.span)
                for k, v in td.params.items():
                    if k == "INTERVAL":
                        tt = self.expr(v, scope, T.TIME)
                        c = self.const_value(v, scope)
                        if tt is None or not T.base_of(tt).is_time or not isinstance(c, int):
                            self.err("E013", v.span, "INTERVAL must be a TIME constant, e.g. T#20ms")
                        elif c <= 0:
                            self.err("E029", v.span, "INTERVAL must be positive")
                        else:
                            tm.interval = c
                    elif k == "PRIORITY":
                        c = self.const_value(v, scope)
                        if not isinstance(c, int):
                            self.err("E029", v.span, "PRIORITY must be an integer constant")
                        else:
                            tm.priority = c
                    elif k == "SINGLE":
                        if isinstance(v, A.Name):
                            gs = self.p.global_names.get(v.name.lower())
                            if not gs:
                                self.err("E010", v.span, f"SINGLE refers to unknown variable '{v.name}'")
                            else:
                                tm.single = gs[0].pyname
                        else:
                            self.err("E013", v.span, "SINGLE must name a BOOL variable")
                    else:
                        self.err("E016", v.span, f"unknown task parameter '{k}' (INTERVAL, SINGLE, PRIORITY)")
                if any(t.name.lower() == td.name.lower() for t in cm.tasks):
                    self.err("E011", td.span, f"task '{td.name}' is declared twice")
                cm.tasks.append(tm)
            for pc in res.programs:
                pou = self.p.pous.get(pc.type_name.lower())
                if pou is None or pou.pou_kind != "PROGRAM":
                    self.err("E028", pc.span, f"'{pc.type_name}' is not a PROGRAM")
                    continue
                if pc.task and not any(t.name.lower() == pc.task.lower() for t in cm.tasks):
                    self.err("E028", pc.span, f"unknown task '{pc.task}'")
                    continue
                if any(i.name.lower() == pc.instance.lower() for i in cm.instances):
                    self.err("E011", pc.span, f"program instance '{pc.instance}' is declared twice")
                    continue
                im = InstanceModel(pc.instance, pou, pc.task, res.name, [], pc.span)
                for a in pc.args:
                    p = pou.vars.get(a.name.lower())
                    if p is None or p.section not in _SECTIONS_PARAM:
                        self.err("E016", a.span, f"{pou.name} has no parameter '{a.name}'")
                        continue
                    if a.output:
                        self.expr(a.value, scope)
                    else:
                        vt = self.expr(a.value, scope, p.type)
                        self.assignable(a.value, vt, p.type, a.value.span, "pass")
                    im.args.append((p, a.value, a.output))
                cm.instances.append(im)
        for b in cfg.var_blocks:
            if b.kind == "VAR_CONFIG":
                for d in b.decls:
                    if self._config_path_type(cm, d) is not None:
                        cm.var_config.append((d.path or [], d.location, d.init, d.type, d.span))
        self.p.configs.append(cm)

    def _config_path_type(self, cm: ConfigModel, d: A.VarDecl):
        """Check a VAR_CONFIG entry `inst.fb.var AT %QX0.0 : T := v;`; its variable's type or None."""
        path = d.path or []
        inst = next((i for i in cm.instances if path and i.name.lower() == path[0].lower()), None)
        if inst is None:
            self.err("E010", d.span, f"VAR_CONFIG: no program instance named '{path[0] if path else ''}'")
            return None
        t: T.Type = inst.type
        for name in path[1:]:
            ut = T.unalias(t)
            sym = ut.vars.get(name.lower()) if isinstance(ut, T.POUType) else None
            if sym is None:
                self.err("E010", d.span, f"VAR_CONFIG: {'.'.join(path)}: '{name}' is not a variable of {ut}")
                return None
            t = sym.type
        want = self.resolve_type(d.type, None)
        if not self._same_type(want, t):
            self.err("E013", d.type.span, f"VAR_CONFIG: {'.'.join(path)} is {t}, not {want}")
            return None
        if d.location:
            self._check_location(d.location, t, d.span)
        if d.init is not None:
            self.check_initializer(d.init, t, None)
        return t

    def _implicit_configuration(self) -> None:
        progs = [p for p in self.p.pous.values() if p.pou_kind == "PROGRAM" and not p.library]
        cm = ConfigModel("", implicit=True)
        cm.tasks.append(TaskModel("main", 0, 0))
        for p in progs:
            cm.instances.append(InstanceModel(p.name, p, "main", "", [], p.decl.span if p.decl else None))
        self.p.configs.append(cm)

    # ================================================================ cycles
    def _check_cycles(self) -> None:
        """A type may not contain itself, and POUs may not call themselves (IEC forbids recursion)."""
        def members(t):
            t = T.unalias(t)
            if isinstance(t, T.ArrayType):
                return members(t.element)
            if isinstance(t, T.StructType):
                return [m.type for m in t.members.values()]
            if isinstance(t, T.POUType) and t.pou_kind != "FUNCTION":
                return [v.type for v in t.vars.values() if v.section not in ("VAR_EXTERNAL", "VAR_IN_OUT")]
            return []

        def leaf(t):
            t = T.unalias(t)
            while isinstance(t, T.ArrayType):
                t = T.unalias(t.element)
            return t if isinstance(t, (T.StructType, T.POUType)) else None

        for t in list(self.p.types.values()) + list(self.p.pous.values()):
            start = leaf(t)
            if start is None:
                continue
            seen, stack = set(), [leaf(m) for m in members(start)]
            while stack:
                x = stack.pop()
                if x is None or id(x) in seen:
                    continue
                if x is start:
                    span = self._decl_span.get(start.name.lower())
                    self.err("E012", span or Span("<types>", 0, 0), f"'{start.name}' contains itself")
                    break
                seen.add(id(x))
                stack.extend(leaf(m) for m in members(x))
        # calls
        for pou in self.p.pous.values():
            seen, stack = set(), list(self._calls.get(pou.name.lower(), ()))
            while stack:
                name, span = stack.pop()
                if name == pou.name.lower():
                    self.err("E032", span, f"{pou.name} calls itself (recursion is not allowed in IEC 61131-3)")
                    break
                if name in seen:
                    continue
                seen.add(name)
                stack.extend(self._calls.get(name, ()))

    # ================================================================ warnings
    def _warn_unused(self) -> None:
        for pou in self.p.pous.values():
            if pou.library:
                continue
            for sym in pou.vars.values():
                if sym.section in ("VAR", "VAR_TEMP") and not sym.used and not sym.location:
                    self.warn("W002", sym.span, f"variable '{sym.name}' is never used")
