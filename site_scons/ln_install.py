"""Install helpers shared by the SConscripts: launcher scripts for Python entry points.

A launcher puts PYTHONDIR on sys.path (it need not be on the interpreter's default path,
e.g. /usr/local/lib/python3/dist-packages on Debian) and calls the entry point's main().
"""

import os

LAUNCHER = '''#!/usr/bin/env python3
# %(name)s launcher: runs %(module)s, installed in PYTHONDIR.
import sys

PYTHONDIR = %(pythondir)r
if PYTHONDIR not in sys.path:
    sys.path.insert(0, PYTHONDIR)
from %(module)s import main  # noqa: E402

sys.exit(main())
'''


def _write_launcher(target, source, env):
    with open(target[0].abspath, 'w') as f:
        f.write(source[0].read())
    os.chmod(target[0].abspath, 0o755)


def install_launcher(env, name, module):
    """Install $PREFIX/bin/NAME running MODULE.main() from $PYTHONDIR; returns the nodes."""
    text = LAUNCHER % {'name': name, 'module': module, 'pythondir': env.subst('$PYTHONDIR')}
    return env.Command('$INSTALL_ROOT/bin/' + name, env.Value(text),
                       env.Action(_write_launcher, 'Install launcher: "$TARGET"'))
