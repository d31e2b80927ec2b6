"""A toy backend, whole in this folder (issue 35): plain Python with the ``math`` module, one configuration per call.

It shows what adding a backend takes: this folder (the emitter with its printer and template, the loader, the
reserved words) and one line of symkin.backends.BACKENDS, which tests/backends/test_toy_backend.py adds.
"""

from __future__ import annotations

from typing import Any


class ToyBackend:
    """Emits ``<model>_toy.py``: each generated function as plain Python returning nested lists."""

    name = "toy"
    loader: str | None = "toy_backend.loader"

    def emit(self, code: Any) -> dict[str, str | bytes]:
        from sympy.printing.pycode import PythonCodePrinter

        from symkin.backends.layout import nonzero_elements
        from symkin.backends.templating import provenance, render_from

        printer = PythonCodePrinter({"standard": "python3"})
        functions = []
        for f in code.functions:
            spec = f.spec
            outputs = []
            for out, entries in zip(spec.outputs, f.outputs):
                size = 1
                for n in out.shape:
                    size *= n
                values = ["0.0"] * size
                for index, e in nonzero_elements(out, entries):
                    flat = 0
                    for k, n in zip(index, out.shape):
                        flat = flat * n + k
                    values[flat] = printer.doprint(e)
                outputs.append({"name": out.name, "shape": list(out.shape), "entries": values})
            functions.append({
                "name": spec.name,
                "vectors": [{"name": v.name, "symbols": [str(s) for s in v.symbols]} for v in spec.vector_inputs],
                "params": [{"name": p.name, "default": repr(p.default_value)} for p in spec.parameter_inputs],
                "temporaries": [{"name": str(s), "code": printer.doprint(e)} for s, e in f.temporaries],
                "outputs": outputs})
        text = render_from("toy_backend", "templates/module.py.j2",
                           provenance=provenance("toy_backend/templates/module.py.j2", code.name, code.hash),
                           functions=functions)
        return {f"{code.name}_toy.py": text}

    def reserved_words(self) -> frozenset[str]:
        """A word the toy's own code takes (its output helper)."""
        return frozenset({"shaped"})
