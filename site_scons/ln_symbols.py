"""The functions a C header declares with an export macro (LN_EXPORT, LN_ADMIN_API,
LN_NDN_EXPORT), read from the header text: the SConscripts build libln_admin.so's version
script from them and `scons check` compares them with what the shared libraries export."""

import re

# What libln_admin.so exports besides ln_admin.h: the last error of its own copy of libln
# (the manager's ctypes layer reads the detail of a failed admin call there).
ADMIN_ALSO_EXPORTS = ('ln_last_error',)

_COMMENT = re.compile(r'/\*.*?\*/|//[^\n]*', re.S)
_DIRECTIVE = re.compile(r'^[ \t]*#(?:[^\n]*\\\n)*[^\n]*', re.M)


def declared(text, macro):
    """Sorted names of the functions `text` (a header) declares as `macro` ... name(...)."""
    code = _DIRECTIVE.sub('', _COMMENT.sub(' ', text))
    pattern = r'\b' + re.escape(macro) + r'\b[^;{}()]*?\b([A-Za-z_]\w*)\s*\('
    return sorted(set(re.findall(pattern, code)))


def declared_in(paths, macro):
    """declared() over several header files."""
    names = set()
    for path in paths:
        with open(path) as f:
            names.update(declared(f.read(), macro))
    return sorted(names)


def version_script(names):
    """A GNU ld version script that exports `names` and hides everything else."""
    exported = ''.join(f'    {n};\n' for n in names)
    return '{\n  global:\n' + exported + '  local: *;\n};\n'
