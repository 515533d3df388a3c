"""Job import: formats, placement, validation, optimization, estimate and preview.

Pure blocking functions (the server runs them in a worker process); see
docs/INTERNALS.md, "Importer API".
"""

from .eta import eta
from .models import ImportFailed, ImportOptions, ImportResult, MachineProfile
from .patterns import PATTERNS
from .pipeline import import_file, import_pattern
from .program import resume_preamble

__all__ = [
    "PATTERNS",
    "ImportFailed",
    "ImportOptions",
    "ImportResult",
    "MachineProfile",
    "eta",
    "import_file",
    "import_pattern",
    "resume_preamble",
]
