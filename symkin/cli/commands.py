"""The subcommands of ``symkin``, in the order ``--help`` lists them."""

from __future__ import annotations

from symkin.cli import (
    bench_cmd,
    cache_cmd,
    check_cmd,
    crosscheck_cmd,
    derive_cmd,
    excite_cmd,
    gci_cmd,
    identify_cmd,
    ik_cmd,
    optimize_cmd,
    rate_cmd,
    simulate_cmd,
    structure_cmd,
    sweep_cmd,
    view_cmd,
    workspace_cmd,
)

REGISTRY = [
    derive_cmd.register,
    check_cmd.register_check,
    check_cmd.register_quantities,
    crosscheck_cmd.register_crosscheck,
    crosscheck_cmd.register_export,
    workspace_cmd.register,
    view_cmd.register,
    gci_cmd.register,
    optimize_cmd.register,
    sweep_cmd.register,
    structure_cmd.register_mobility,
    structure_cmd.register_topologies,
    bench_cmd.register,
    ik_cmd.register,
    simulate_cmd.register,
    rate_cmd.register,
    identify_cmd.register,
    excite_cmd.register,
    cache_cmd.register,
]
