"""Optional dependencies: a clear message naming the extra to install instead of a bare
``ModuleNotFoundError`` (the simulator installs light; RL needs ``.[rl]``, the sweep ``.[ray]``)."""
from __future__ import annotations

import importlib.util

__all__ = ["EXTRAS", "RL_COMMAND_MODULES", "missing_modules", "require_extra"]

#: the import names each extra provides (pyproject.toml [project.optional-dependencies])
EXTRAS = {
    "rl": ("gymnasium", "stable_baselines3", "torch", "yaml", "osqp"),
    "ray": ("ray",),
    "peer": ("moordyn",),
    "dev": ("pytest", "hypothesis"),
}
#: what the training and evaluation command lines import (the clairvoyant planner's osqp only when used)
RL_COMMAND_MODULES = ("gymnasium", "stable_baselines3", "torch", "yaml")


def missing_modules(modules) -> list[str]:
    """The names in ``modules`` that cannot be imported here."""
    out = []
    for m in modules:
        try:
            if importlib.util.find_spec(m) is None:
                out.append(m)
        except (ImportError, ValueError):   # a module set to None in sys.modules, a broken package
            out.append(m)
    return out


def require_extra(extra: str, who: str, modules=None) -> None:
    """Exit with code 2 and one line naming the extra when its modules are missing (for scripts and
    command lines: ``require_extra("rl", "train.py")``)."""
    miss = missing_modules(modules if modules is not None else EXTRAS[extra])
    if miss:
        import sys
        print(f"{who}: needs the optional '{extra}' dependencies (missing: {', '.join(miss)}); install them with "
              f'pip install ".[{extra}]" in a checkout, or pip install "towenv[{extra}]"', file=sys.stderr)
        raise SystemExit(2)
