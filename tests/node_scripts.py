"""Generated JavaScript run by Node.js from the tests: the objects a program writes as JSON, and the forward
assembly of a model's script (``assemble`` and ``assembly_jacobian``: issue 63)."""

from __future__ import annotations

import json
import shutil
import subprocess

import numpy as np

#: Gauss-Newton's step tolerance and its bound on the steps (the runtime's defaults).
TOLERANCE, ITERATIONS = 1e-12, 50


def node_json(program: str) -> list[dict]:
    """The list of objects the Node.js ``program`` writes as JSON, their lists as float arrays (null: NaN)."""
    node = shutil.which("node")
    assert node, "Node.js is needed to test the JavaScript backend: install it (Debian: apt-get install nodejs)"
    out = subprocess.run([node, "-e", program], capture_output=True, text=True, check=True).stdout
    return [{key: np.array(value, dtype=float) if isinstance(value, list) else value for key, value in found.items()}
            for found in json.loads(out.replace("null", "NaN"))]


def script_forward(module, q: np.ndarray, s: np.ndarray, p: np.ndarray) -> list[dict]:
    """assemble(q, s, p) and assembly_jacobian at its result of the script ``module`` for each sample, by Node.js."""
    program = (f"const m = require({json.dumps(str(module))});"
               f"const [q, s, p] = [{json.dumps(q.tolist())}, {json.dumps(s.tolist())}, {json.dumps(p.tolist())}];"
               f"process.stdout.write(JSON.stringify(q.map((qk, k) => {{"
               f"const found = m.assemble(qk, s[k], p[k], {{}}, {{max_iterations: {ITERATIONS}, tolerance: {TOLERANCE}}});"
               f"return Object.assign(found, {{J: m.assembly_jacobian(qk, found.s, found.p, {{}})}}); }})));")
    return node_json(program)
