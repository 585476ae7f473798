"""ctypes declarations of libln's parameter block functions (ln.h, "parameter blocks"), each
declared once, with the errcheck of _clientlib (raise the class of a negative code)."""

from __future__ import annotations

import ctypes

from ._clientlib import _check
from ._libln import _declare

c_double, c_int, c_size_t, c_uint32 = ctypes.c_double, ctypes.c_int, ctypes.c_size_t, \
    ctypes.c_uint32
c_char_p, c_void_p = ctypes.c_char_p, ctypes.c_void_p

LN_PARAMETER_MIN = 0x1
LN_PARAMETER_MAX = 0x2
LN_PARAMETER_READ_ONLY = 0x4
LN_PARAMETER_MAX_NAME = 63


class ParameterDesc(ctypes.Structure):
    _fields_ = [("name", c_char_p), ("type", c_char_p), ("count", c_uint32),
                ("flags", c_uint32), ("description", c_char_p), ("input", c_void_p),
                ("output", c_void_p), ("min", c_double), ("max", c_double)]


# int validator(ln_parameter_block*, int index, const char* name, const void* value,
#               char* reason, size_t reason_size, void* user_data); runs on libln's service
# thread (ctypes takes the GIL for it).
VALIDATOR = ctypes.CFUNCTYPE(c_int, c_void_p, c_int, c_char_p, c_void_p, c_void_p, c_size_t,
                             c_void_p)

ln_parameter_block_create = _declare("ln_parameter_block_create", c_int,
                                     [c_void_p, ctypes.POINTER(c_void_p), c_char_p], _check)
ln_parameter_block_add = _declare("ln_parameter_block_add", c_int,
                                  [c_void_p, ctypes.POINTER(ParameterDesc)], _check)
ln_parameter_block_set_validator = _declare("ln_parameter_block_set_validator", c_int,
                                            [c_void_p, VALIDATOR, c_void_p], _check)
ln_parameter_block_register = _declare("ln_parameter_block_register", c_int, [c_void_p],
                                       _check)
ln_parameter_block_update = _declare("ln_parameter_block_update", c_int, [c_void_p], _check)
ln_parameter_block_changed = _declare("ln_parameter_block_changed", c_int, [c_void_p, c_int],
                                      _check)
ln_parameter_block_service_name = _declare("ln_parameter_block_service_name", c_char_p,
                                           [c_void_p])
ln_parameter_block_destroy = _declare("ln_parameter_block_destroy", c_int, [c_void_p], _check)
