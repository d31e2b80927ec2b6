"""Write the hostile model corpus: tests/corpus/hostile/NN-name.yaml and manifest.json.

Run ``python tests/corpus/make_hostile_corpus.py`` after changing a case; the files are
committed and tests/model/test_hostile_corpus.py checks every one of them (exit code 2, located
message with the recorded fragment, nothing written, nothing executed).

Two sources:

* :data:`CASES`, written by hand, one per class of hostile input (broken YAML, wrong types,
  missing and duplicate keys, absurd sizes, cycles, degenerate geometry, code execution,
  path traversal, huge numbers, billion laughs, deep nesting, bad bytes, long lines);
* mutants of a valid model drawn by hypothesis (:func:`fuzz_cases`, derandomized so the
  corpus is reproducible), kept with the message symkin gives them.

Payloads that try to run code all try to create the file ``pwned`` in the working
directory: the tests run every case in an empty directory and check that it stays empty.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

HERE = Path(__file__).resolve().parent / "hostile"
TESTS = Path(__file__).resolve().parent.parent

#: The valid model every hostile variant starts from (shared with the fuzz strategies and test_model_errors).
BASE = (Path(__file__).resolve().parent / "base_model.yaml").read_text()


def replace(old: str, new: str) -> str:
    assert old in BASE, old
    return BASE.replace(old, new, 1)


def rows(count: int) -> str:
    return "".join(f"      - [j{i}, R, 0, 0, l1, 0]\n" for i in range(count))


LAUGHS = "".join(f"l{i}: &l{i} [{', '.join([f'*l{i - 1}'] * 10)}]\n" for i in range(1, 10))

#: (name, content, expected message fragment, expected line or None)
CASES: list[tuple[str, str | bytes, str, int | None]] = [
    # broken YAML
    ("yaml-unclosed-bracket", replace("task_space: [x, y]", "task_space: [x, y"), "YAML syntax error", 13),
    ("yaml-bad-indentation", replace("  l2: 0.2\n", "    l2: 0.2\n"), "YAML syntax error", 4),
    ("yaml-tab-indentation", replace("  l2: 0.2\n", "\tl2: 0.2\n"), "YAML syntax error", 4),
    ("yaml-unclosed-quote", replace("name: arm", 'name: "arm'), "YAML syntax error", None),
    ("yaml-two-documents", BASE + "---\nname: other\n", "expected a single document", 15),
    ("yaml-empty-file", "", "the file is empty", None),
    ("yaml-only-comments", "# nothing here\n# at all\n", "the file is empty", None),
    ("yaml-top-level-list", "- name: arm\n- serial: {}\n", "expected a mapping", 1),
    ("yaml-top-level-scalar", "just text\n", "expected a mapping", 1),
    ("yaml-mapping-in-scalar", replace("name: arm", "name: arm: robot"), "YAML syntax error", 1),
    # wrong types
    ("type-serial-number", replace("serial:\n  dh:", "serial: 5\nunused:\n  dh:"), "expected a mapping", 6),
    ("type-rows-mapping", replace("    rows:\n", "    rows: {a: 1}\n    other:\n"), "expected a list of DH rows", 9),
    ("type-name-number", replace("name: arm", "name: 12"), "a name must be a string, got int", 1),
    ("type-parameters-list", replace("parameters:\n  l1: {value: 0.1, unit: m}\n  l2: 0.2\n  m2: 0.5\n",
                                     "parameters: [1, 2]\n"), "expected a mapping", 2),
    ("type-limits-string", replace("limits: [-pi, pi]", "limits: abc"), "expected a list of bounds", 11),
    ("type-boolean-length", replace("l2: 0.2", "l2: yes"), "boolean", 4),
    ("type-gravity-scalar", BASE + "gravity: 9.81\n", "expected a list of components", 15),
    ("type-active-not-bool", replace("limits: [-pi, pi]", "limits: [-pi, pi], active: maybe"),
     "'active' must be true or false", 11),
    ("type-task-space-number", replace("task_space: [x, y]", "task_space: 3"), "expected a list of task-space components", 12),
    ("type-mass-list", replace("mass: m2", "mass: [1, 2]"), "expected a number or an expression, got list", 14),
    ("type-convention-list", replace("convention: classic", "convention: [classic]"), "unknown DH convention", 8),
    ("type-key-not-string", BASE + "1: one\n", "mapping keys must be plain strings", 15),
    ("type-joint-type-list", replace("type: R, theta: 0", "type: [], theta: 0"), "a joint type must be a name", 11),
    # missing and duplicate keys
    ("missing-serial", BASE.split("serial:")[0] + "task_space: [x, y]\n", "the model declares no mechanism", None),
    ("missing-dh-convention", replace("    convention: classic\n", ""), "missing required key 'convention'", 7),
    ("missing-body-mass", replace("{link: link2, mass: m2}", "{link: link2}"), "missing required key 'mass'", 14),
    ("missing-row-alpha", replace("a: l2, alpha: 0,", "a: l2,"), "missing required key 'alpha'", 11),
    ("both-dh-and-chain", replace("serial:\n", "serial:\n  chain: [{name: q0}]\n"), "exactly one of 'dh:'", 6),
    ("duplicate-top-level-key", BASE + "task_space: [x]\n", "duplicate key 'task_space'", 15),
    ("duplicate-parameter", replace("  m2: 0.5\n", "  m2: 0.5\n  l1: 0.3\n"), "duplicate key 'l1'", 6),
    ("duplicate-joint-name", replace("name: theta2", "name: theta1"), "duplicate joint name 'theta1'", 6),
    ("duplicate-scene-output", BASE + "scene: {outputs: [fk, fk]}\n", "'fk' appears twice", 15),
    ("duplicate-scene-backend", BASE + "scene: {backends: [numpy, numpy]}\n", "'numpy' appears twice", 15),
    ("unknown-top-level-key", replace("task_space: [x, y]", "task_spaces: [x, y]"), "did you mean 'task_space'", 12),
    ("parameter-value-and-expr", replace("l2: 0.2", "l2: {value: 0.2, expr: l1}"), "exactly one of 'value:'", 4),
    # absurd sizes
    ("size-too-many-joints", replace("      - [theta1, R, 0, 0, l1, 0]\n", rows(200)), "more than the limit of 64", 6),
    ("size-vector-1000-components", BASE + f"gravity: [{', '.join(['0'] * 1000)}]\n", "expected 3 components, got 1000",
     15),
    ("size-dh-row-100-entries", replace("[theta1, R, 0, 0, l1, 0]", "[theta1, R, " + ", ".join(["0"] * 98) + "]"),
     "a DH row has 6 entries", 10),
    ("size-100-digit-number", replace("l2: 0.2", "l2: 0." + "1" * 100), "more than 40 digits", 4),
    ("size-5000-digit-integer", replace("l2: 0.2", "l2: " + "9" * 5000), "(5000 characters)", 4),
    ("size-3000-character-expression", replace("l2: 0.2", "l2: " + "+".join(["l1"] * 1000)), "longer than 2000", 4),
    ("size-20kb-key", BASE + "? " + "k" * 20_000 + "\n: 1\n", "(20000 characters)", 15),
    ("size-name-too-long", replace("name: arm", "name: " + "a" * 65), "not a valid name", 1),
    # cycles
    ("cycle-derived-parameters", replace("  m2: 0.5\n", "  m2: 0.5\n  u: {expr: v + 1}\n  v: {expr: 2*u}\n"),
     "derived parameters form a cycle", None),
    ("cycle-self-reference", replace("  m2: 0.5\n", "  m2: 0.5\n  u: {expr: u + 1}\n"), "cycle: u -> u", 6),
    ("cycle-recursive-alias", BASE + "references: &r [*r]\n", "an alias refers to a node that contains it", 15),
    # zero-length and degenerate geometry (parallel legs come with issue 5)
    ("zero-joint-axis", "name: arm\nserial:\n  chain:\n    - {name: q1, axis: [0, 0, 0]}\n", "the joint axis is the zero vector",
     4),
    ("zero-rows", replace("    rows:\n      - [theta1, R, 0, 0, l1, 0]\n      - {name: theta2, type: R, theta: 0, d: 0, a: l2, "
                          "alpha: 0, limits: [-pi, pi]}\n", "    rows: []\n").replace(
        "bodies:\n  - {link: link2, mass: m2}\n", ""), "the chain has no joints", 6),
    ("zero-chain", "name: arm\nserial:\n  chain: []\n", "the chain has no joints", 2),
    ("negative-mass", replace("m2: 0.5", "m2: -0.5"), "negative mass", 14),
    # issue 61: it blocks only the outputs that use the inertias - this scene asks for M
    ("unphysical-inertia", replace("{link: link2, mass: m2}", "{link: link2, mass: m2, inertia: {xx: 0, yy: 4, zz: 3}}")
     + "scene:\n  outputs: [fk, mass_matrix]\n", "not physical", 14),
    ("limits-reversed", replace("limits: [-pi, pi]", "limits: [pi, -pi]"), "not below", 11),
    ("multi-dof-joint-in-serial-chain", replace("[theta1, R,", "[theta1, S,"), "several degrees of freedom", 10),
    ("link-name-not-in-chain", replace("{link: link2,", "{link: link9,"), "unknown link", 14),
    # code execution attempts: every payload would create ./pwned
    ("exec-python-object-apply", replace("l2: 0.2", "l2: !!python/object/apply:os.system ['touch pwned']"), "not allowed",
     4),
    ("exec-python-object-new", BASE + "description: !!python/object/new:os.system {args: ['touch pwned']}\n",
     "not allowed", 15),
    ("exec-python-name", replace("l2: 0.2", "l2: !!python/name:os.system"), "not allowed", 4),
    ("exec-python-module", replace("l2: 0.2", "l2: !!python/module:os"), "not allowed", 4),
    ("exec-local-tag", replace("l2: 0.2", "l2: !pwn 0.2"), "not allowed", 4),
    ("exec-binary-tag", replace("l2: 0.2", "l2: !!binary dG91Y2ggcHduZWQ="), "not allowed", 4),
    ("exec-set-tag", BASE + "description: !!set {a, b}\n", "not allowed", 15),
    ("exec-merge-key", replace("  l2: 0.2\n", "  base: &b {value: 1}\n  l2: {<<: *b}\n"), "merge keys", 5),
    ("exec-dunder-import", replace("a: l2,", "a: \"__import__('os').system('touch pwned')\","), "invalid expression", 11),
    ("exec-eval-call", replace("a: l2,", "a: eval(l1),"), "unknown function 'eval'", 11),
    ("exec-open-call", replace("l2: 0.2", "l2: open(pwned)"), "unknown function 'open'", 4),
    ("exec-lambda", replace("l2: 0.2", "l2: 'lambda: 0'"), "unexpected character ':'", 4),
    ("exec-attribute-access", replace("a: l2,", "a: l2.__class__,"), "unexpected character '.'", 11),
    ("exec-subscript", replace("l2: 0.2", "l2: 'l1[0]'"), "unexpected character '['", 4),
    ("exec-string-literal", replace("l2: 0.2", "l2: \"'touch pwned'\""), "unexpected character", 4),
    ("exec-sympy-constructor", replace("l2: 0.2", "l2: Symbol(x)"), "unknown function 'Symbol'", 4),
    ("exec-semicolon", replace("l2: 0.2", "l2: '0.2; import os'"), "unexpected character ';'", 4),
    ("exec-scene-output", BASE + "scene: {outputs: [\"__import__('os').system('touch pwned')\"]}\n", "unknown output", 15),
    # path traversal in names
    ("path-model-name-dotdot", replace("name: arm", "name: ../../tmp/pwned"), "not a valid name", 1),
    ("path-model-name-absolute", replace("name: arm", "name: /tmp/pwned"), "not a valid name", 1),
    ("path-model-name-nul", replace("name: arm", 'name: "arm\\0x"'), "not a valid name", 1),
    ("path-link-name", replace("{name: theta2, type: R,", "{name: theta2, link: ../evil, type: R,"), "not a valid name",
     11),
    ("path-scene-backend", BASE + "scene: {backends: ['../../numpy']}\n", "unknown backend", 15),
    ("path-reserved-name", replace("name: arm", "name: numpy"), "reserved word", 1),
    # huge numbers
    ("huge-power-tower", replace("l2: 0.2", "l2: 9**9**9"), "too large", 4),
    ("huge-power", replace("l2: 0.2", "l2: 10**400"), "too large", 4),
    ("huge-yaml-integer", replace("l2: 0.2", "l2: 1" + "0" * 400), "more than 40 digits", 4),
    ("huge-decimal-exponent", replace("l2: 0.2", "l2: 1e400"), "decimal exponent", 4),
    ("huge-yaml-float", replace("l2: 0.2", "l2: 1.0e+400"), "the value is infinite or NaN", 4),
    ("huge-yaml-infinity", replace("l2: 0.2", "l2: .inf"), "infinite or NaN", 4),
    ("huge-exp", replace("l2: 0.2", "l2: exp(1000)"), "the value is too large", 4),
    ("huge-nested-exp", replace("l2: 0.2", "l2: exp(exp(10))"), "the value is too large", 4),
    ("huge-division-by-zero", replace("l2: 0.2", "l2: {expr: 1/(l1 - l1)}"), "division by zero", 4),
    ("huge-tan-pole", replace("l2: 0.2", "l2: tan(pi/2)"), "infinite or undefined", 4),
    ("huge-acos-domain", replace("l2: 0.2", "l2: acos(2)"), "not a real number", 4),
    # billion laughs, deep nesting
    ("laughs-billion", "l0: &l0 [lol, lol, lol, lol, lol, lol, lol, lol, lol, lol]\n" + LAUGHS,
     "expands to more than", None),
    ("nesting-deep-flow-sequences", "name: arm\ndescription: " + "[" * 2000 + "]" * 2000 + "\n",
     "nested deeper than 64 levels", 2),
    ("nesting-deep-flow-mappings", "name: arm\ndescription: " + "{a: " * 1500 + "1" + "}" * 1500 + "\n",
     "nested deeper than 64 levels", 2),
    ("nesting-deep-expression", replace("l2: 0.2", "l2: " + "(" * 60 + "1" + ")" * 60), "nested deeper", 4),
    # bytes that are not text
    ("bytes-not-utf8", BASE.encode() + b"description: caf\xe9\n", "not UTF-8", None),
    ("bytes-nul", BASE.encode().replace(b"name: arm", b"name: a\x00rm"), "U+0000 is not allowed", 1),
    ("bytes-control-character", BASE.encode().replace(b"l2: 0.2", b"l2: 0.2\x07"), "U+0007 is not allowed", 4),
    ("bytes-utf16", BASE.encode("utf-16"), "not UTF-8", None),
    # extremely long lines
    ("long-line-flow-mapping", replace("bodies:\n  - {link: link2, mass: m2}\n",
                                       "bodies:\n  - {link: link2, mass: m2, " + ", ".join(f"k{i}: {i}" for i in range(3000))
                                       + "}\n"), "unknown key 'k0'", 14),
    ("long-line-description-and-error", replace("name: arm", "name: arm\ndescription: " + "x" * 50_000)
     .replace("l2: 0.2", "l2: nope"), "undefined name 'nope'", 5),
    # found by the fuzz test in CI: a YAML list where a link name belongs
    ("body-link-not-a-name", replace("{link: link2, mass: m2}", "{link: [], mass: m2}"), "bodies[0].link", 14),
]


def fuzz_cases(count: int = 14) -> list[tuple[str, str, str, int | None]]:
    """Mutants of the valid model drawn by hypothesis (derandomized: the same ones every run) that
    symkin rejects, the first one of each kind of message, with that message recorded."""
    import sys

    from hypothesis import HealthCheck, Phase, given, settings

    sys.path.insert(0, str(TESTS))
    from fuzz_strategies import hostile_models

    from symkin.errors import ModelError
    from symkin.model import model_from_text

    kept: dict[str, tuple[str, str, int | None]] = {}

    @settings(max_examples=600, derandomize=True, database=None, phases=[Phase.generate], deadline=None,
              suppress_health_check=list(HealthCheck))
    @given(hostile_models)
    def collect(text: str) -> None:
        if len(kept) >= count:
            return
        try:
            model_from_text(text, "arm", "fuzz.yaml")
        except ModelError as err:
            problem = err.problems[0]
            kind = re.sub(r"'[^']*'|\d+", "_", problem.message)[:40]
            if kind not in kept and problem.message.isprintable():
                kept[kind] = (text, problem.message[:60], problem.line)

    collect()
    cases = []
    for text, message, line in kept.values():
        words = re.findall(r"[a-z]+", message.lower())[:5]
        cases.append(("fuzz-" + "-".join(words), text, message, line))
    return cases


def write() -> None:
    HERE.mkdir(parents=True, exist_ok=True)
    for old in HERE.glob("*.yaml"):
        old.unlink()
    manifest = []
    for number, (name, content, fragment, line) in enumerate(CASES + fuzz_cases(), start=1):
        assert re.fullmatch(r"[a-z0-9-]+", name), name
        file = f"{number:03d}-{name}.yaml"
        data = content.encode() if isinstance(content, str) else content
        (HERE / file).write_bytes(data)
        manifest.append({"file": file, "expect": fragment, "line": line})
    (HERE / "manifest.json").write_text(json.dumps(manifest, indent=1) + "\n")
    print(f"{len(manifest)} cases written to {HERE}")


if __name__ == "__main__":
    write()
