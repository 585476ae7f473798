"""ln_generate: message definitions -> C, C++ and Python types with one byte layout.

The package reads LN message definition files (mds), builds a typed model with a
fixed packed little-endian layout, and emits code for each language from it.
"""

from .diagnostics import Diagnostic, Location, MdError
from .model import Field, MessageDef, Primitive, Struct
from .registry import MdRegistry, default_md_dirs

__version__ = "0.1.0"

__all__ = [
    "Diagnostic",
    "Field",
    "Location",
    "MdError",
    "MdRegistry",
    "MessageDef",
    "Primitive",
    "Struct",
    "__version__",
    "default_md_dirs",
]
