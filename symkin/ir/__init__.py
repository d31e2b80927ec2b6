"""The backend-neutral intermediate representation: function specs and their optimized form."""

from symkin.ir.spec import FunctionSpec, InputSpec, OptimizedFunction, OutputSpec, combine_functions, make_function

__all__ = ["FunctionSpec", "InputSpec", "OptimizedFunction", "OutputSpec", "combine_functions", "make_function"]
