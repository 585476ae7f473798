"""Identifier rules shared by the resolver and the emitters.

A field name must be usable unchanged in C, C++ and Python, so words reserved in
any of the three (or by the generated Python classes) are refused up front.
"""

from __future__ import annotations

import keyword
import re

C_KEYWORDS = frozenset(
    """auto break case char const continue default do double else enum extern float for
    goto if inline int long register restrict return short signed sizeof static struct
    switch typedef union unsigned void volatile while bool true false _Bool _Complex
    _Imaginary _Alignas _Alignof _Atomic _Generic _Noreturn _Static_assert _Thread_local
    alignas alignof static_assert thread_local typeof nullptr constexpr""".split()
)
CPP_KEYWORDS = frozenset(
    """and and_eq asm bitand bitor catch char8_t char16_t char32_t class compl concept
    const_cast consteval constinit co_await co_return co_yield decltype delete
    dynamic_cast explicit export friend mutable namespace new noexcept not not_eq
    operator or or_eq private protected public reinterpret_cast requires static_cast
    template this throw try typeid typename using virtual wchar_t xor xor_eq""".split()
)
PY_KEYWORDS = frozenset(keyword.kwlist)
#: Attributes of the generated Python classes that a field would shadow.
PY_CLASS_NAMES = frozenset(
    "MD_NAME SIGNATURE LAYOUT_HASH SIZE KIND MESSAGES to_dict from_dict update copy _fields_ "
    "_pack_ _anonymous_ _objects _b_base_ _b_needsfree_ from_buffer from_buffer_copy "
    "from_address from_param in_dll".split()
)
#: Macros that <stddef.h>/<stdint.h> or the compilers' GNU modes define.
_C_MACRO_RE = re.compile(
    r"(U?INT(8|16|32|64|PTR|MAX)_(MAX|MIN|C)|U?INT_(LEAST|FAST)(8|16|32|64)_(MAX|MIN)"
    r"|(SIZE|PTRDIFF|WCHAR|WINT|SIG_ATOMIC)_(MAX|MIN)|NULL|offsetof|linux|unix|i386)\Z"
)


def reserved_reason(name: str) -> str | None:
    """Why `name` cannot be a field name, or None."""
    if name in C_KEYWORDS:
        return f"field name '{name}' is a reserved word in C"
    if name in CPP_KEYWORDS:
        return f"field name '{name}' is a reserved word in C++"
    if re.match(r"_[A-Z]", name):
        return f"field name '{name}' is reserved in C (underscore and capital letter)"
    if _C_MACRO_RE.match(name):
        return f"field name '{name}' is a macro of the C headers or compilers"
    if name in PY_KEYWORDS:
        return f"field name '{name}' is a reserved word in Python"
    if name in PY_CLASS_NAMES:
        return f"field name '{name}' is reserved by the generated Python classes"
    if name.startswith("_ln_") or name.startswith("__"):
        return f"field name '{name}' uses a reserved prefix ('_ln_' or '__')"
    return None


def c_name(md_name: str) -> str:
    """`robot/joint_state` -> `robot_joint_state` (prefix of C type and constants)."""
    return md_name.replace("/", "_")
