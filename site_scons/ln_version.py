"""The release version of links_and_nodes, read from the one place it is written down: the
LN_VERSION_* macros of libln/include/ln/ln.h.  The SConscripts take ln.pc's and the CMake
package's version from here.  Four copies cannot be derived at build time and are checked
instead (version_mismatches(), which the build runs, and tests/python/distribution/
test_version.py): debian/changelog (Debian's convention), the `__version__` of the two
Python packages, which must work in a wheel without the checkout, and the VS Code
extension's package.json (scripts/build-vsix also writes ln.h's version into the .vsix)."""

import os
import re

_MACROS = re.compile(r'^#define (LN_VERSION_MAJOR|LN_VERSION_MINOR|LN_VERSION_PATCH|'
                     r'LN_SOVERSION) (\d+)$', re.M)
_PYTHON = re.compile(r'^__version__ = "([^"]*)"$', re.M)
_CHANGELOG = re.compile(r'\A[a-z0-9][a-z0-9.+-]* \(([^)]+)\) ')
_PACKAGE_JSON = re.compile(r'^  "version": "([^"]*)",$', re.M)  # the top level's, 2 blanks in
# Relative to the checkout: the copies and how to find the version in each.
COPIES = (('debian/changelog', _CHANGELOG),
          ('python/links_and_nodes/__init__.py', _PYTHON),
          ('ln_generate/__init__.py', _PYTHON),
          ('editors/vscode/package.json', _PACKAGE_JSON))


def version_macros(header_text):
    """{'LN_VERSION_MAJOR': '0', ..., 'LN_SOVERSION': '1'} from the text of ln.h."""
    found = dict(_MACROS.findall(header_text))
    missing = {'LN_VERSION_MAJOR', 'LN_VERSION_MINOR', 'LN_VERSION_PATCH',
               'LN_SOVERSION'} - set(found)
    if missing:
        raise ValueError(f"ln.h lacks #define {', '.join(sorted(missing))}")
    return found


def version_string(macros):
    """'MAJOR.MINOR.PATCH' of version_macros()."""
    return '{LN_VERSION_MAJOR}.{LN_VERSION_MINOR}.{LN_VERSION_PATCH}'.format(**macros)


def copied_versions(root):
    """{relative path: the version written there, or None if none is found} of the COPIES
    under the checkout `root` (one without debian/, e.g. an sdist, has fewer)."""
    found = {}
    for path, pattern in COPIES:
        if not os.path.exists(os.path.join(root, path)):
            continue
        with open(os.path.join(root, path), encoding='utf-8') as f:
            match = pattern.search(f.read())
        found[path] = match.group(1) if match else None
    return found


def version_mismatches(root, version):
    """One message per copy under the checkout `root` that does not say `version` (ln.h's)."""
    return [f'{path}: {copy or "no version found"}, but ln.h says {version}'
            for path, copy in copied_versions(root).items() if copy != version]
