"""Validate a composed YAML document and build the frozen :class:`~symkin.model.schema.Model`.

The format is documented in ``docs/model-format.md``.  Every problem is collected with its
location (file, line, column, key path) and a suggested fix; if any is found a single
:class:`~symkin.errors.ModelError` lists them all, so a user fixes a file in one pass.
"""

from __future__ import annotations

import difflib
import hashlib
import math
from collections.abc import Callable, Iterable
from typing import Any

import numpy as np
import sympy

from symkin.errors import ModelError, Problem
from symkin.geometry import rotation_matrix
from symkin.model import coordinates
from symkin.model.expressions import ExpressionError, parse_expression
from symkin.model.names import name_problem
from symkin.model.schema import (
    Body,
    DerivedParameter,
    Friction,
    Joint,
    JointType,
    Model,
    Op,
    Parameter,
    Rotation,
    Scene,
    Translation,
    Vec3,
)
from symkin.model.yaml_source import Document, KeyPath, shorten

#: Version of the model format; part of the model hash.
FORMAT_VERSION = 1
#: Most joints of one chain (exact expressions grow with the chain; beyond this, derivation
#: would run for hours).
MAX_JOINTS = 64

TOP_LEVEL_KEYS = ("name", "description", "references", "parameters", "serial", "parallel", "task_space",
                  "bodies", "gravity", "friction", "scene")

JOINT_TYPES = {"R": JointType.REVOLUTE, "revolute": JointType.REVOLUTE,
               "P": JointType.PRISMATIC, "prismatic": JointType.PRISMATIC}
#: Joint types that exist in legs of parallel mechanisms but not in a serial chain.
MULTI_DOF_JOINT_TYPES = ("U", "S", "C", "E", "H")

DH_CONVENTIONS = {"classic": "classic", "distal": "classic", "modified": "modified", "proximal": "modified"}
DH_COLUMNS = ("name", "type", "theta", "d", "a", "alpha")

TASK_COMPONENTS = ("x", "y", "z", "roll", "pitch", "yaw", "wx", "wy", "wz")
TASK_SHORTHANDS = {"pose": ("x", "y", "z", "wx", "wy", "wz"), "position": ("x", "y", "z")}

ZERO = sympy.Integer(0)
ONE = sympy.Integer(1)
X_AXIS: Vec3 = (ONE, ZERO, ZERO)
Y_AXIS: Vec3 = (ZERO, ONE, ZERO)
Z_AXIS: Vec3 = (ZERO, ZERO, ONE)


def _describe(value: Any) -> str:
    if value is None:
        return "nothing"
    if isinstance(value, bool):
        return f"the boolean {value}"
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, list):
        return f"a list of {len(value)}"
    return f"'{shorten(value)}'"


class _Reader:
    """Typed access to document values that records located problems instead of raising."""

    def __init__(self, doc: Document):
        self.doc = doc
        self.problems: list[Problem] = []
        #: Names usable in expressions: parameter symbols and inlined derived parameters.
        self.names: dict[str, sympy.Expr] = {}
        #: Default value of every free parameter symbol (for physical plausibility checks).
        self.defaults: dict[sympy.Symbol, sympy.Expr] = {}
        #: Parameters whose own definition failed: uses of them are not reported again.
        self.invalid: set[str] = set()
        #: Links of joints whose definition failed: bodies on them are not reported as unknown.
        self.invalid_links: set[str] = set()

    def fail(self, path: KeyPath, message: str, fix: str) -> None:
        self.problems.append(self.doc.problem(path, message, fix))

    def mapping(self, path: KeyPath, value: Any, required: Iterable[str] = (),
                optional: Iterable[str] = ()) -> dict[str, Any] | None:
        """``value`` as a mapping with only known keys and every required key."""
        required, optional = tuple(required), tuple(optional)
        if not isinstance(value, dict):
            self.fail(path, f"expected a mapping, got {_describe(value)}",
                      f"write a mapping with the keys {', '.join(required + optional)}")
            return None
        allowed = required + optional
        for key in value:
            if key not in allowed:
                close = difflib.get_close_matches(key, allowed, n=1)
                hint = f"did you mean '{close[0]}'? " if close else ""
                self.fail(path + (key,), f"unknown key '{shorten(key)}'", f"{hint}allowed keys here: {', '.join(allowed)}")
        for key in required:
            if key not in value:
                self.fail(path, f"missing required key '{key}'", f"add '{key}:'")
        return value

    def sequence(self, path: KeyPath, value: Any, length: int | None = None, what: str = "items") -> list[Any] | None:
        if not isinstance(value, list):
            self.fail(path, f"expected a list of {what}, got {_describe(value)}", f"write a YAML list of {what}")
            return None
        if length is not None and len(value) != length:
            self.fail(path, f"expected {length} {what}, got {len(value)}", f"write exactly {length} {what}")
            return None
        return value

    def string(self, path: KeyPath, value: Any) -> str | None:
        if not isinstance(value, str):
            self.fail(path, f"expected text, got {_describe(value)}", "write text (quote it if needed)")
            return None
        return value

    def name(self, path: KeyPath, value: Any) -> str | None:
        problem = name_problem(value)
        if problem:
            self.fail(path, problem, "rename it, e.g. 'theta1', 'l1' or 'link2'")
            return None
        return value

    def expr(self, path: KeyPath, value: Any, names: dict[str, sympy.Expr] | None = None) -> sympy.Expr | None:
        """Parse the expression at ``path``; numbers are read from their raw text (exact decimals)."""
        text = value
        if isinstance(value, (int, float)) and not isinstance(value, bool) and not (
                isinstance(value, float) and not math.isfinite(value)):
            text = self.doc.raw.get(path, value)  # .inf and .nan go to the parser as floats
        try:
            return parse_expression(text, self.names if names is None else names)
        except ExpressionError as err:
            if err.undefined_name is not None and err.undefined_name in self.invalid:
                return None  # the parameter's own definition is already reported
            problem = self.doc.problem(path, f"invalid expression '{shorten(text)}': {err}", err.fix)
            if problem.column is not None and isinstance(text, str):
                problem = Problem(problem.file, problem.line, problem.column + err.column, problem.key,
                                  problem.message, problem.fix)
            self.problems.append(problem)
            return None

    def vector3(self, path: KeyPath, value: Any) -> Vec3 | None:
        items = self.sequence(path, value, 3, "components")
        if items is None:
            return None
        parts = [self.expr(path + (i,), v) for i, v in enumerate(items)]
        if any(p is None for p in parts):
            return None
        return (parts[0], parts[1], parts[2])

    def default_value(self, expr: sympy.Expr) -> float | None:
        """Numeric value of ``expr`` at the parameters' defaults, or None if not numeric."""
        value = sympy.sympify(expr).xreplace(self.defaults)
        if value.free_symbols:
            return None
        try:
            return float(value)
        except TypeError:
            return None


def build_model(doc: Document, stem: str) -> Model:
    """Validate ``doc`` and build its :class:`Model`.

    Args:
        doc: the composed YAML document.
        stem: file name without extension, the default model name.

    Raises:
        ModelError: listing every problem found.
    """
    r = _Reader(doc)
    data = r.mapping((), doc.data, optional=TOP_LEVEL_KEYS)
    if data is None:
        raise ModelError(r.problems)

    name = _model_name(r, data, stem)
    description = r.string(("description",), data.get("description", "")) or ""
    references = _references(r, data)
    parameters, derived = _parameters(r, data.get("parameters", {}))
    if ("serial" in data) == ("parallel" in data):
        r.fail((), "the model declares no mechanism" if "serial" not in data else
               "the model declares both a serial chain and a parallel mechanism",
               "write exactly one of 'serial:' or 'parallel:' (see docs/model-format.md)")
        raise ModelError(r.problems)
    parallel = None
    if "serial" in data:
        joints, base, tcp = _serial(r, data["serial"])
        _check_name_clashes(r, parameters, derived, joints)
        task_space = _task_space(r, data.get("task_space", "position"))
        coordinate_names = tuple(j.name for j in joints)
    else:
        from symkin.model.parallel_build import build_parallel, check_parallel_names, parallel_task_space

        joints, base, tcp = (), (), ()
        parallel = build_parallel(r, data["parallel"])
        if parallel is None:
            raise ModelError(r.problems)
        task_space = parallel_task_space(r, data, parallel)
        check_parallel_names(r, parameters, derived, parallel)
        coordinate_names = tuple(j.variables[j.active] for leg in parallel.legs for j in leg.joints
                                 if j.active is not None)
    links = tuple(j.link for j in joints)
    bodies = _bodies(r, data.get("bodies", []), links)
    gravity = r.vector3(("gravity",), data["gravity"]) if "gravity" in data else (ZERO, ZERO, ZERO)
    friction = _friction(r, data.get("friction", {}), coordinate_names)
    scene = _scene(r, data.get("scene", {}), parameters,
                   ("fk", "jacobian") if parallel is None else ("closure", "closure_jacobians"))

    if r.problems:
        raise ModelError(r.problems)
    digest = hashlib.sha256(f"symkin-model-format-{FORMAT_VERSION}\n{doc.canonical_json()}".encode()).hexdigest()
    return Model(
        name=name,
        description=description.strip(),
        references=references,
        source=doc.file,
        hash=f"sha256:{digest}",
        parameters=parameters,
        derived_parameters=derived,
        joints=joints,
        base=base,
        tcp=tcp,
        task_space=task_space,
        bodies=bodies,
        gravity=gravity or (ZERO, ZERO, ZERO),
        friction=friction,
        scene=scene,
        parallel=parallel,
        locations=dict(doc.marks),
    )


def _model_name(r: _Reader, data: dict[str, Any], stem: str) -> str:
    if "name" in data:
        return r.name(("name",), data["name"]) or "invalid"
    problem = name_problem(stem)
    if problem:
        r.fail((), f"the model has no 'name:' and the file name is not usable as one: {problem}",
               "add a line 'name: my_robot' at the top of the file")
        return "invalid"
    return stem


def _references(r: _Reader, data: dict[str, Any]) -> tuple[str, ...]:
    refs = r.sequence(("references",), data.get("references", []), what="citations")
    if refs is None:
        return ()
    return tuple(s for i, v in enumerate(refs) if (s := r.string(("references", i), v)) is not None)


# --------------------------------------------------------------------------- parameters

def _parameters(r: _Reader, section: Any) -> tuple[tuple[Parameter, ...], tuple[DerivedParameter, ...]]:
    """Free parameters (constant default values) and derived parameters (``expr:``).

    Derived parameters may refer to free and to other derived parameters in any order; they
    are inlined, so they never become inputs of generated functions.  Cycles are errors.
    """
    path: KeyPath = ("parameters",)
    section = r.mapping(path, section, optional=tuple(section) if isinstance(section, dict) else ())
    if section is None:
        return (), ()
    free: list[Parameter] = []
    pending: dict[str, tuple[KeyPath, Any, str, str]] = {}
    for pname, spec in section.items():
        ppath = path + (pname,)
        if r.name(ppath, pname) is None:
            continue
        unit = doc = ""
        value_key = "value"
        if isinstance(spec, dict):
            spec = r.mapping(ppath, spec, optional=("value", "expr", "unit", "doc"))
            if spec is None:
                continue
            unit = r.string(ppath + ("unit",), spec.get("unit", "")) or ""
            doc = r.string(ppath + ("doc",), spec.get("doc", "")) or ""
            if ("value" in spec) == ("expr" in spec):
                r.fail(ppath, "a parameter needs exactly one of 'value:' (a number) or 'expr:' (a formula)",
                       "write 'value: 0.1' for a free parameter or 'expr: l1/2' for a derived one")
                continue
            value_key = "value" if "value" in spec else "expr"
            raw = spec[value_key]
            vpath = ppath + (value_key,)
        else:
            raw, vpath = spec, ppath
        if value_key == "expr":
            pending[pname] = (vpath, raw, unit, doc)
            continue
        value = r.expr(vpath, raw, names={})
        if value is None:
            r.invalid.add(pname)
            continue
        symbol = sympy.Symbol(pname, real=True)
        free.append(Parameter(pname, symbol, value, unit, doc))
        r.names[pname] = symbol
        r.defaults[symbol] = value
    derived = _resolve_derived(r, pending)
    return tuple(free), derived


def _resolve_derived(r: _Reader, pending: dict[str, tuple[KeyPath, Any, str, str]]) -> tuple[DerivedParameter, ...]:
    """Parse derived parameters in dependency order; report cycles and unknown names."""
    resolved: list[DerivedParameter] = []
    waiting = dict(pending)
    while waiting:
        progress = False
        blocked: dict[str, str] = {}
        for pname, (vpath, raw, unit, doc) in list(waiting.items()):
            try:
                definition = parse_expression(_raw_text(r, vpath, raw), r.names)
            except ExpressionError as err:
                if err.undefined_name in waiting:
                    blocked[pname] = err.undefined_name
                    continue
                r.expr(vpath, raw)  # records the located problem
                r.invalid.add(pname)
                del waiting[pname]
                progress = True
                continue
            resolved.append(DerivedParameter(pname, definition, unit, doc))
            r.names[pname] = definition
            del waiting[pname]
            progress = True
        if not progress:
            for pname in sorted(blocked):
                cycle = _cycle_from(pname, blocked)
                r.fail(waiting[pname][0], f"derived parameters form a cycle: {' -> '.join(cycle)}",
                       "define at least one parameter of the cycle by a number ('value:')")
            break
    return tuple(resolved)


def _raw_text(r: _Reader, path: KeyPath, value: Any) -> Any:
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return r.doc.raw.get(path, value)
    return value


def _cycle_from(start: str, edges: dict[str, str]) -> list[str]:
    seen = [start]
    node = edges.get(start)
    while node is not None and node not in seen:
        seen.append(node)
        node = edges.get(node)
    return seen + ([node] if node is not None else [])


# --------------------------------------------------------------------------- serial chain

def _serial(r: _Reader, section: Any) -> tuple[tuple[Joint, ...], tuple[Op, ...], tuple[Op, ...]]:
    path: KeyPath = ("serial",)
    section = r.mapping(path, section, optional=("dh", "chain", "base", "tcp"))
    if section is None:
        return (), (), ()
    joints: list[Joint] = []
    if ("dh" in section) == ("chain" in section):
        r.fail(path, "a serial mechanism needs exactly one of 'dh:' (a DH table) or 'chain:' (a joint chain)",
               "keep one of the two sections")
    elif "dh" in section:
        joints = _dh_table(r, path + ("dh",), section["dh"])
    else:
        joints = _chain(r, path + ("chain",), section["chain"])
    base = _frame_ops(r, path + ("base",), section["base"]) if "base" in section else ()
    tcp = _frame_ops(r, path + ("tcp",), section["tcp"]) if "tcp" in section else ()
    if not joints and not r.problems:
        r.fail(path, "the chain has no joints", "declare at least one joint")
    if len(joints) > MAX_JOINTS:
        r.fail(path, f"the chain has {len(joints)} joints, more than the limit of {MAX_JOINTS}",
               "split the mechanism; symbolic expressions grow with every joint of a chain")
    _check_unique(r, [(path, j.name) for j in joints], "joint")
    _check_unique(r, [(path, j.link) for j in joints], "link")
    return tuple(joints), base or (), tcp or ()


def _check_unique(r: _Reader, items: list[tuple[KeyPath, str]], what: str) -> None:
    seen: set[str] = set()
    for path, item in items:
        if item in seen:
            r.fail(path, f"duplicate {what} name '{item}'", f"give every {what} its own name")
        seen.add(item)


def _joint_type(r: _Reader, path: KeyPath, value: Any) -> JointType | None:
    if not isinstance(value, str):
        r.fail(path, f"a joint type must be a name, got {_describe(value)}", "use 'R' (revolute) or 'P' (prismatic)")
        return None
    if value in JOINT_TYPES:
        return JOINT_TYPES[value]
    if value in MULTI_DOF_JOINT_TYPES:
        r.fail(path, f"joint type '{value}' has several degrees of freedom; a serial chain uses R or P joints",
               "decompose it into R joints (U = 2 R, S = 3 R with intersecting axes, C = R + P)")
    else:
        r.fail(path, f"unknown joint type {_describe(value)}", "use 'R' (revolute) or 'P' (prismatic)")
    return None


def _ops(*ops: Op) -> tuple[Op, ...]:
    """Drop identity operations (zero angle, zero translation)."""
    kept = []
    for op in ops:
        if isinstance(op, Rotation) and op.angle == 0:
            continue
        if isinstance(op, Translation) and all(c == 0 for c in op.vector):
            continue
        kept.append(op)
    return tuple(kept)


_JOINT_EXTRAS = ("link", "limits", "velocity_limit", "effort_limit", "active")


def _dh_table(r: _Reader, path: KeyPath, section: Any) -> list[Joint]:
    """Joints from a DH table (seed sec. 3.1, eq. 8.12 and Table 8.3).

    classic (distal):   ^{i-1}T_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i)
    modified (proximal, Craig): ^{i-1}T_i = Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(theta_i) Tz(d_i),
    where row i holds alpha_{i-1} and a_{i-1} as in Craig's tables.
    The joint coordinate adds to theta (revolute) or d (prismatic).
    """
    section = r.mapping(path, section, required=("convention", "rows"))
    if section is None or "convention" not in section or "rows" not in section:
        return []
    convention = DH_CONVENTIONS.get(section["convention"]) if isinstance(section["convention"], str) else None
    if convention is None:
        r.fail(path + ("convention",), f"unknown DH convention {_describe(section['convention'])}",
               "use 'classic' (distal, Denavit-Hartenberg) or 'modified' (proximal, Craig)")
        return []
    rows = r.sequence(path + ("rows",), section["rows"], what="DH rows")
    if rows is None:
        return []
    joints = []
    for i, row in enumerate(rows):
        rpath = path + ("rows", i)
        fields = _dh_row_fields(r, rpath, row)
        if fields is None or any(k not in fields for k in ("name", "theta", "d", "a", "alpha")):
            r.invalid_links.add(_declared_link(fields, i))
            continue  # the missing keys are reported
        jname = r.name(rpath + ("name",), fields["name"])
        jtype = _joint_type(r, rpath + ("type",), fields.get("type", "R"))
        values = {k: r.expr(rpath + (k,), fields[k]) for k in ("theta", "d", "a", "alpha")}
        extras = _joint_extras(r, rpath, fields, default_link=f"link{i + 1}")
        if jname is None or jtype is None or any(v is None for v in values.values()) or extras is None:
            r.invalid_links.add(_declared_link(fields, i))
            continue
        theta, d, a, alpha = values["theta"], values["d"], values["a"], values["alpha"]
        revolute = jtype is JointType.REVOLUTE
        if convention == "classic":
            before = () if revolute else _ops(Rotation(Z_AXIS, theta))
            after = _ops(*((Translation((ZERO, ZERO, d)),) if revolute else ()),
                         Translation((a, ZERO, ZERO)), Rotation(X_AXIS, alpha))
        else:
            before = _ops(Rotation(X_AXIS, alpha), Translation((a, ZERO, ZERO)),
                          *(() if revolute else (Rotation(Z_AXIS, theta),)))
            after = _ops(Translation((ZERO, ZERO, d))) if revolute else ()
        joints.append(Joint(name=jname, type=jtype, axis=Z_AXIS, offset=theta if revolute else d,
                            before=before, after=after, **extras))
    return joints


def _dh_row_fields(r: _Reader, path: KeyPath, row: Any) -> dict[str, Any] | None:
    """A DH row as a mapping; list rows are [name, type, theta, d, a, alpha(, [lower, upper])]."""
    if isinstance(row, list):
        if len(row) not in (6, 7):
            r.fail(path, f"a DH row has 6 entries [{', '.join(DH_COLUMNS)}] (and optionally [lower, upper] limits), "
                         f"this one has {len(row)}",
                   "write the row as [name, type, theta, d, a, alpha] or as a mapping with those keys")
            return None
        fields = dict(zip(DH_COLUMNS, row))
        if len(row) == 7:
            fields["limits"] = row[6]
        # List entries are located by index; map the field names onto those paths.
        for k, key in enumerate(list(DH_COLUMNS) + ["limits"]):
            if k < len(row):
                _alias_path(r.doc, path + (k,), path + (key,))
        return fields
    return r.mapping(path, row, required=("name", "theta", "d", "a", "alpha"), optional=("type",) + _JOINT_EXTRAS)


def _declared_link(fields: Any, index: int) -> str:
    """The link a joint entry declares (or its default name), even if the entry is invalid."""
    link = fields.get("link") if isinstance(fields, dict) else None
    return link if isinstance(link, str) else f"link{index + 1}"


def _alias_path(doc: Document, source: KeyPath, alias: KeyPath) -> None:
    """Make every location under ``source`` also known under ``alias``."""
    for key in [k for k in doc.marks if k[:len(source)] == source]:
        doc.marks.setdefault(alias + key[len(source):], doc.marks[key])
        if key in doc.raw:
            doc.raw.setdefault(alias + key[len(source):], doc.raw[key])


def _chain(r: _Reader, path: KeyPath, section: Any) -> list[Joint]:
    """Joints of a URDF-like chain: parent_T_link = Trans(xyz) Rz(yaw) Ry(pitch) Rx(roll) Motion(axis, q)."""
    items = r.sequence(path, section, what="joints")
    if items is None:
        return []
    joints = []
    for i, item in enumerate(items):
        jpath = path + (i,)
        item = r.mapping(jpath, item, required=("name",), optional=("type", "axis", "origin", "offset") + _JOINT_EXTRAS)
        if item is None or "name" not in item:
            continue
        jname = r.name(jpath + ("name",), item["name"])
        jtype = _joint_type(r, jpath + ("type",), item.get("type", "R"))
        axis = _unit_axis(r, jpath + ("axis",), item["axis"]) if "axis" in item else Z_AXIS
        before = _frame_ops(r, jpath + ("origin",), item["origin"]) if "origin" in item else ()
        offset = r.expr(jpath + ("offset",), item["offset"]) if "offset" in item else ZERO
        extras = _joint_extras(r, jpath, item, default_link=f"link{i + 1}")
        if None in (jname, jtype, axis, before, offset, extras):
            r.invalid_links.add(_declared_link(item, i))
            continue
        joints.append(Joint(name=jname, type=jtype, axis=axis, offset=offset, before=before, after=(), **extras))
    return joints


def _unit_axis(r: _Reader, path: KeyPath, value: Any) -> Vec3 | None:
    vec = r.vector3(path, value)
    if vec is None:
        return None
    if any(c.free_symbols for c in vec):
        r.fail(path, "a joint axis must be made of numbers", "write the axis as numbers, e.g. [0, 0, 1]")
        return None
    norm = sympy.sqrt(sum(c**2 for c in vec))
    if norm == 0:
        r.fail(path, "the joint axis is the zero vector", "give the axis direction, e.g. [0, 0, 1]")
        return None
    return (vec[0] / norm, vec[1] / norm, vec[2] / norm)


def _frame_ops(r: _Reader, path: KeyPath, value: Any) -> tuple[Op, ...] | None:
    """A fixed frame {xyz: [...], rpy: [...]}: Trans(xyz) Rz(yaw) Ry(pitch) Rx(roll) (URDF convention).

    A list of such frames is their composition, applied in order (the fixed joints between
    two moving joints of a URDF chain).
    """
    if isinstance(value, list):
        parts = [_frame_ops(r, path + (i,), item) for i, item in enumerate(value)]
        return None if any(p is None for p in parts) else tuple(op for part in parts for op in part)  # type: ignore
    section = r.mapping(path, value, optional=("xyz", "rpy"))
    if section is None:
        return None
    xyz = r.vector3(path + ("xyz",), section["xyz"]) if "xyz" in section else (ZERO, ZERO, ZERO)
    rpy = r.vector3(path + ("rpy",), section["rpy"]) if "rpy" in section else (ZERO, ZERO, ZERO)
    if xyz is None or rpy is None:
        return None
    roll, pitch, yaw = rpy
    return _ops(Translation(xyz), Rotation(Z_AXIS, yaw), Rotation(Y_AXIS, pitch), Rotation(X_AXIS, roll))


def position_limits(r: _Reader, path: KeyPath, value: Any) -> tuple[sympy.Expr, sympy.Expr] | None:
    """Position limits ``[lower, upper]`` (expressions, lower < upper at the default values), or None."""
    bounds = r.sequence(path, value, 2, "bounds [lower, upper]")
    if bounds is None:
        return None
    lower = r.expr(path + (0,), bounds[0])
    upper = r.expr(path + (1,), bounds[1])
    if lower is None or upper is None:
        return None
    lo, hi = r.default_value(lower), r.default_value(upper)
    if lo is not None and hi is not None and not lo < hi:
        r.fail(path, f"the lower limit {lower} is not below the upper limit {upper}",
               "write the limits as [lower, upper]")
        return None
    return lower, upper


def _joint_extras(r: _Reader, path: KeyPath, item: dict[str, Any], default_link: str) -> dict[str, Any] | None:
    """Link name, limits and activity of a joint (keys shared by DH rows and chain joints)."""
    link = r.name(path + ("link",), item["link"]) if "link" in item else default_link
    limits = None
    ok = link is not None
    if "limits" in item:
        limits = position_limits(r, path + ("limits",), item["limits"])
        ok = ok and limits is not None
    extras: dict[str, Any] = {"link": link, "limits": limits}
    for key in ("velocity_limit", "effort_limit"):
        extras[key] = None
        if key in item:
            value = r.expr(path + (key,), item[key])
            numeric = r.default_value(value) if value is not None else None
            if value is None or (numeric is not None and numeric <= 0):
                if value is not None:
                    r.fail(path + (key,), f"{key} must be positive, got {value}", "write a positive number")
                ok = False
            extras[key] = value
    active = item.get("active", True)
    if not isinstance(active, bool):
        r.fail(path + ("active",), f"'active' must be true or false, got {_describe(active)}", "write true or false")
        ok = False
    extras["active"] = active
    return extras if ok else None


def _check_name_clashes(r: _Reader, parameters: tuple[Parameter, ...], derived: tuple[DerivedParameter, ...],
                        joints: tuple[Joint, ...]) -> None:
    taken = {p.name for p in parameters} | {p.name for p in derived}
    for i, joint in enumerate(joints):
        for symbol in coordinates.all_symbol_names(joint.name):
            if symbol in taken:
                r.fail(("parameters", symbol), f"parameter '{symbol}' clashes with the symbol '{symbol}' of "
                                               f"joint '{joint.name}' (joint {i + 1})",
                       f"rename the parameter or the joint '{joint.name}'")


# --------------------------------------------------------------------------- task space, bodies, ...

def _task_space(r: _Reader, value: Any) -> tuple[str, ...]:
    path: KeyPath = ("task_space",)
    if isinstance(value, str):
        if value in TASK_SHORTHANDS:
            return TASK_SHORTHANDS[value]
        r.fail(path, f"unknown task space '{value}'",
               f"use 'pose', 'position' or a list of components from {', '.join(TASK_COMPONENTS)}")
        return ()
    items = r.sequence(path, value, what="task-space components")
    if items is None:
        return ()
    out: list[str] = []
    for i, item in enumerate(items):
        if item not in TASK_COMPONENTS:
            r.fail(path + (i,), f"unknown task-space component {_describe(item)}",
                   f"use components from {', '.join(TASK_COMPONENTS)}")
        elif item in out:
            r.fail(path + (i,), f"task-space component '{item}' appears twice", "list each component once")
        else:
            out.append(item)
    if not items:
        r.fail(path, "the task space is empty", "list at least one component, e.g. [x, y]")
    return tuple(out)


_INERTIA_KEYS = ("xx", "yy", "zz", "xy", "xz", "yz")


def _bodies(r: _Reader, value: Any, links: tuple[str, ...]) -> tuple[Body, ...]:
    path: KeyPath = ("bodies",)
    items = r.sequence(path, value, what="bodies")
    if items is None:
        return ()
    bodies = []
    for i, item in enumerate(items):
        bpath = path + (i,)
        item = r.mapping(bpath, item, required=("link", "mass"), optional=("com", "inertia", "inertia_rpy", "origin"))
        if item is None or "link" not in item or "mass" not in item:
            continue
        link = r.name(bpath + ("link",), item["link"])  # a name, not any YAML value (lists are unhashable)
        if link is None or link in r.invalid_links:
            continue  # its joint is already reported
        if link not in links:
            close = difflib.get_close_matches(str(link), links, n=1)
            hint = f"did you mean '{close[0]}'? " if close else ""
            r.fail(bpath + ("link",), f"unknown link {_describe(link)}", f"{hint}links: {', '.join(links)}")
            continue
        mass = r.expr(bpath + ("mass",), item["mass"])
        com = r.vector3(bpath + ("com",), item["com"]) if "com" in item else (ZERO, ZERO, ZERO)
        inertia = _inertia(r, bpath + ("inertia",), item["inertia"]) if "inertia" in item else sympy.zeros(3, 3)
        if "inertia_rpy" in item and inertia is not None:
            inertia = _rotate_inertia(r, bpath + ("inertia_rpy",), item["inertia_rpy"], inertia)
        if "origin" in item and com is not None and inertia is not None:
            com, inertia = _body_in_link_frame(r, bpath + ("origin",), item["origin"], com, inertia)
        if mass is None or com is None or inertia is None:
            continue
        m = r.default_value(mass)
        if m is not None and m < 0:
            r.fail(bpath + ("mass",), f"negative mass {mass} ({m:g} at the default values)",
                   "a mass is zero or positive")
            continue
        bodies.append(Body(link, mass, com, sympy.ImmutableMatrix(inertia)))
    return tuple(bodies)


def _body_in_link_frame(r: _Reader, path: KeyPath, value: Any, com: Vec3, inertia: sympy.Matrix
                        ) -> tuple[Vec3 | None, sympy.Matrix | None]:
    """com and inertia given in a frame fixed to the link (``origin:``, one frame or a list),
    expressed in the link frame: c_link = p + R c, I_link = R I R^T with link_T_frame = (R, p)."""
    ops = _frame_ops(r, path, value)
    if ops is None:
        return None, None
    R, p = sympy.eye(3), sympy.zeros(3, 1)
    for op in ops:
        if isinstance(op, Rotation):
            R = R * rotation_matrix(op.axis, op.angle)
        else:
            p = p + R * sympy.Matrix(op.vector)
    c = p + R * sympy.Matrix(com)
    return (c[0], c[1], c[2]), R * inertia * R.T


def _inertia(r: _Reader, path: KeyPath, value: Any) -> sympy.Matrix | None:
    """Inertia about the centre of mass: {xx, yy, zz, xy, xz, yz} or a symmetric 3x3 list."""
    if isinstance(value, dict):
        section = r.mapping(path, value, optional=_INERTIA_KEYS)
        if section is None:
            return None
        parts = {k: r.expr(path + (k,), section[k]) if k in section else ZERO for k in _INERTIA_KEYS}
        if any(v is None for v in parts.values()):
            return None
        tensor = sympy.Matrix([[parts["xx"], parts["xy"], parts["xz"]],
                               [parts["xy"], parts["yy"], parts["yz"]],
                               [parts["xz"], parts["yz"], parts["zz"]]])
    else:
        rows = r.sequence(path, value, 3, "rows (or a mapping xx, yy, zz, xy, xz, yz)")
        if rows is None:
            return None
        entries: list[list[sympy.Expr | None]] = []
        for i, row in enumerate(rows):
            cols = r.sequence(path + (i,), row, 3, "entries")
            if cols is None:
                return None
            entries.append([r.expr(path + (i, j), v) for j, v in enumerate(cols)])
        if any(v is None for row in entries for v in row):
            return None
        tensor = sympy.Matrix(entries)
        if (tensor - tensor.T).is_zero_matrix is not True:
            r.fail(path, "the inertia tensor is not symmetric", "make entry [i][j] equal to entry [j][i]")
            return None
    _check_inertia_physical(r, path, tensor)
    return tensor


def _rotate_inertia(r: _Reader, path: KeyPath, value: Any, inertia: sympy.Matrix) -> sympy.Matrix | None:
    """Inertia given in axes rotated by rpy from the link frame (URDF <inertial><origin rpy>):
    I_link = R I R^T with R = Rz(yaw) Ry(pitch) Rx(roll)."""
    rpy = r.vector3(path, value)
    if rpy is None:
        return None
    roll, pitch, yaw = rpy
    R = rotation_matrix(Z_AXIS, yaw) * rotation_matrix(Y_AXIS, pitch) * rotation_matrix(X_AXIS, roll)
    return R * inertia * R.T


def _check_inertia_physical(r: _Reader, path: KeyPath, tensor: sympy.Matrix) -> None:
    """At default parameter values the principal moments are >= 0 and obey the triangle inequality."""
    values = [r.default_value(v) for v in tensor]
    if any(v is None for v in values):
        return
    moments = np.linalg.eigvalsh(np.array(values, dtype=float).reshape(3, 3))
    scale = max(1e-300, float(np.max(np.abs(moments))))
    a, b, c = moments
    if a < -1e-12 * scale or a + b < c - 1e-9 * scale:
        r.fail(path, f"the inertia tensor is not physical (principal moments {a:.6g}, {b:.6g}, {c:.6g})",
               "principal moments must be >= 0 and each at most the sum of the other two")


def _friction(r: _Reader, value: Any, joint_names: tuple[str, ...]) -> tuple[Friction, ...]:
    path: KeyPath = ("friction",)
    section = r.mapping(path, value, optional=joint_names)
    if section is None:
        return ()
    out = []
    for jname, spec in section.items():
        if jname not in joint_names:
            continue  # already reported as unknown key
        fpath = path + (jname,)
        spec = r.mapping(fpath, spec, optional=("viscous", "coulomb", "smoothing_velocity"))
        if spec is None:
            continue
        viscous = r.expr(fpath + ("viscous",), spec["viscous"]) if "viscous" in spec else ZERO
        coulomb = r.expr(fpath + ("coulomb",), spec["coulomb"]) if "coulomb" in spec else ZERO
        smoothing = r.expr(fpath + ("smoothing_velocity",), spec["smoothing_velocity"]) \
            if "smoothing_velocity" in spec else None
        if viscous is None or coulomb is None or ("smoothing_velocity" in spec and smoothing is None):
            continue
        for key, coeff in (("viscous", viscous), ("coulomb", coulomb)):
            v = r.default_value(coeff)
            if v is not None and v < 0:
                r.fail(fpath + (key,), f"negative {key} friction coefficient {coeff}",
                       "friction coefficients are zero or positive")
        if smoothing is not None:
            v = r.default_value(smoothing)
            if smoothing == 0 or (v is not None and v <= 0):
                r.fail(fpath + ("smoothing_velocity",), f"the smoothing velocity must be positive, got {smoothing}",
                       "give the speed below which Coulomb friction fades out, e.g. a parameter v_s: 0.01")
        out.append(Friction(jname, viscous, coulomb, smoothing))
    return tuple(out)


def _scene(r: _Reader, value: Any, parameters: tuple[Parameter, ...],
           default_outputs: tuple[str, ...] = ("fk", "jacobian")) -> Scene:
    """The default request; output and backend names are checked by the pipeline, which knows them."""
    path: KeyPath = ("scene",)
    section = r.mapping(path, value, optional=("outputs", "fixed", "backends", "float32", "combine"))
    default = Scene(outputs=default_outputs)
    if section is None:
        return default

    def names(key: str, check: Callable[[KeyPath, str], bool]) -> tuple[str, ...] | None:
        if key not in section:
            return None
        items = r.sequence(path + (key,), section[key], what="names")
        if items is None:
            return None
        out = []
        for i, item in enumerate(items):
            if isinstance(item, str) and item in out:
                r.fail(path + (key, i), f"'{shorten(item)}' appears twice", f"list each of the {key} once")
            elif isinstance(item, str) and check(path + (key, i), item):
                out.append(item)
            elif not isinstance(item, str):
                r.fail(path + (key, i), f"expected a name, got {_describe(item)}", "write a name")
        return tuple(out)

    pnames = {p.name for p in parameters}

    def is_parameter(ipath: KeyPath, item: str) -> bool:
        if item in pnames:
            return True
        close = difflib.get_close_matches(item, pnames, n=1)
        hint = f"did you mean '{close[0]}'? " if close else ""
        r.fail(ipath, f"'{shorten(item)}' is not a free parameter of the model", f"{hint}list names declared under 'parameters:'")
        return False

    fixed_value = section.get("fixed")
    if fixed_value == "all":
        fixed: tuple[str, ...] | None = tuple(p.name for p in parameters)
    else:
        fixed = names("fixed", is_parameter)
    outputs = names("outputs", lambda _p, _i: True)
    backends = names("backends", lambda _p, _i: True)
    float32 = section.get("float32", False)
    if not isinstance(float32, bool):
        r.fail(path + ("float32",), f"'float32' must be true or false, got {_describe(float32)}",
               "write true or false")
        float32 = False
    combine = None if section.get("combine", "all") == "all" else names("combine", lambda _p, _i: True)
    return Scene(outputs=outputs if outputs is not None else default.outputs,
                 fixed=fixed or (),
                 backends=backends if backends is not None else default.backends,
                 float32=float32,
                 combine=combine)
