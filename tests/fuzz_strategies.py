"""Hypothesis strategies that turn a valid model file into hostile variants.

Used by tests/model/test_hostile_corpus.py (bounded fuzzing in the suite) and by
tests/corpus/make_hostile_corpus.py (mutants kept in the corpus).
"""

from __future__ import annotations

import copy
from pathlib import Path

import hypothesis.strategies as st
import yaml

#: The valid model the strategies damage (tests/corpus/base_model.yaml, as the hostile corpus).
BASE = (Path(__file__).resolve().parent / "corpus" / "base_model.yaml").read_text()

#: Values a hostile file puts where a model expects something else; code payloads would touch ./pwned.
HOSTILE_VALUES = [
    None, True, False, 0, -1, 10**30, 1e308, -1e-308, float("inf"), float("nan"), "", " ", "x" * 300, [], {},
    [[[]]], {"a": {"b": {"c": []}}}, "__import__('os').system('touch pwned')", "eval('1')", "../../pwned",
    "/etc/passwd", "9**9**9", "1e999", "10**301", "pi/0", "sqrt(-1)", "l1/0", "exp(999)", "acos(3)", "l1**l2",
    "deg(", "(((", "l1 l2", "R", "P", "S", "classic", "fk", "numpy", "theta1", "link2", "pose", "lambda: 0",
    "a\x00b", "\u202eevil", "\t", "-", "*", "&", "!!python/object", "0x1F", "1_000", "+.5e-3", "1/3",
]

KEYS = ["name", "type", "theta", "d", "a", "alpha", "limits", "link", "mass", "com", "inertia", "value", "expr",
        "unit", "scene", "outputs", "backends", "fixed", "convention", "rows", "chain", "axis", "origin",
        "gravity", "friction", "viscous", "bogus", "__class__", "<<"]


def _paths(node, prefix=()):
    yield prefix
    if isinstance(node, dict):
        for key, value in node.items():
            yield from _paths(value, prefix + (key,))
    elif isinstance(node, list):
        for index, value in enumerate(node):
            yield from _paths(value, prefix + (index,))


def _parent(doc, path):
    node = doc
    for part in path[:-1]:
        node = node[part]
    return node


@st.composite
def mutated_document(draw) -> str:
    """BASE with 1-3 structural mutations (replace, delete, add, duplicate), dumped as YAML."""
    doc = yaml.safe_load(BASE)
    for _ in range(draw(st.integers(1, 3))):
        paths = [p for p in _paths(doc) if p]
        if not paths:
            break
        path = draw(st.sampled_from(paths))
        parent = _parent(doc, path)
        operation = draw(st.sampled_from(["replace", "replace", "delete", "add", "duplicate"]))
        if operation == "replace":
            parent[path[-1]] = copy.deepcopy(draw(st.sampled_from(HOSTILE_VALUES)))
        elif operation == "delete":
            del parent[path[-1]]
        elif operation == "add" and isinstance(parent, dict):
            parent[draw(st.sampled_from(KEYS))] = copy.deepcopy(draw(st.sampled_from(HOSTILE_VALUES)))
        elif operation == "duplicate" and isinstance(parent, list):
            parent.append(copy.deepcopy(parent[path[-1]]))
    return yaml.safe_dump(doc, sort_keys=False, allow_unicode=True)


HOSTILE_CHARACTERS = ":[]{},-#&*!|>'\"%@`\t\n \\?=~^$\x00\x07\x1b\u00e9\u202e\ufeff0123456789.eEpi()+/"


@st.composite
def mutated_text(draw) -> str:
    """BASE with characters inserted, deleted or replaced at random places (syntax-level damage)."""
    text = BASE
    for _ in range(draw(st.integers(1, 4))):
        position = draw(st.integers(0, len(text)))
        operation = draw(st.sampled_from(["insert", "delete", "replace", "truncate"]))
        chunk = draw(st.text(alphabet=HOSTILE_CHARACTERS, min_size=1, max_size=4))
        if operation == "insert":
            text = text[:position] + chunk + text[position:]
        elif operation == "delete":
            text = text[:position] + text[position + len(chunk):]
        elif operation == "replace":
            text = text[:position] + chunk + text[position + len(chunk):]
        else:
            text = text[:position]
    return text


hostile_models = st.one_of(mutated_document(), mutated_text())
