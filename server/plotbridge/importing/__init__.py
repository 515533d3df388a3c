"""Job import: formats, placement, validation, optimization, estimate and preview.

Pure blocking functions (the server runs them in a worker process); see
docs/INTERNALS.md, "Importer API".

The public names load their modules on first use (PEP 562), so the server
process, which needs only `eta`, never loads numpy and svgelements.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

# Loaded at once: numpy-free (it lives with the motion model).
from ..motion.eta import eta

if TYPE_CHECKING:
    from .models import ImportFailed, ImportOptions, ImportResult, MachineProfile
    from .patterns import PATTERNS
    from .pipeline import import_file, import_pattern

_LAZY = {
    "PATTERNS": ".patterns",
    "ImportFailed": ".models",
    "ImportOptions": ".models",
    "ImportResult": ".models",
    "MachineProfile": ".models",
    "import_file": ".pipeline",
    "import_pattern": ".pipeline",
}

__all__ = [
    "PATTERNS",
    "ImportFailed",
    "ImportOptions",
    "ImportResult",
    "MachineProfile",
    "eta",
    "import_file",
    "import_pattern",
]


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(import_module(module, __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
