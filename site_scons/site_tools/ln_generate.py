"""SCons tool for ln_generate: env.LnGenerate(target, [md names]) turns message definitions
into a C, C++ or Python source file, with dependencies on every md file involved (including
imports) and on the generator itself.  Used by this project's build and installed for users.

    env = Environment(tools=['default', 'ln_generate'], toolpath=[...])
    env.LnGenerate('messages.h', ['robot/joint_state'], LN_MD_DIRS=['msg_defs'])

Construction variables:
    LN_MD_DIRS   searched in order, before the generator's built-in message definitions
                 and $LN_MESSAGE_DEFINITION_DIRS; relative to the calling SConscript
    LN_LANG      c, cpp or python; by default from the target's suffix
    PYTHON       interpreter for a source-tree generator; default: the one running SCons
    LN_GENERATE  command that runs the generator (also from the environment); found
                 automatically when unset
    LN_GENERATE_COMSTR  progress message instead of the command line

The generator is found, in this order: $LN_GENERATE; the source checkout this file lives in
(run as `$PYTHON -m ln_generate` with PYTHONPATH set to the checkout, nothing installed);
the ln_generate executable of the installation this file belongs to; ln_generate on PATH.
"""

import ast
import os
import re
import shutil
import subprocess
import sys

import SCons.Action
import SCons.Builder
import SCons.Errors
import SCons.Node.Python
import SCons.Scanner
import SCons.Subst
import SCons.Util

_HERE = os.path.dirname(os.path.abspath(__file__))
# Source checkout: <root>/site_scons/site_tools; installation: <prefix>/share/links_and_nodes/
# site_scons/site_tools, with the launcher in <prefix>/bin.
_SHARE = os.path.dirname(os.path.dirname(_HERE))
_SOURCE_PACKAGE = os.path.join(_SHARE, 'ln_generate')
_INSTALLED_EXE = os.path.join(os.path.dirname(os.path.dirname(_SHARE)), 'bin', 'ln_generate')

_SUFFIX_LANG = {'.h': 'c', '.hpp': 'cpp', '.hh': 'cpp', '.hxx': 'cpp', '.py': 'python'}
_LANGS = ('c', 'cpp', 'python')


class _Generator:
    """How to run the generator: argv prefix, extra environment, files it is made of."""

    def __init__(self, argv, extra_env, files):
        self.argv = argv
        self.extra_env = extra_env
        self.files = files


def _python_files(package_dir):
    found = []
    for folder, subdirs, files in os.walk(package_dir):
        subdirs[:] = sorted(d for d in subdirs if d != '__pycache__')
        found += [os.path.join(folder, f) for f in sorted(files) if f.endswith('.py')]
    return found


def _launcher_package(exe):
    """Package directory named by an installed launcher's PYTHONDIR line, if readable."""
    try:
        with open(exe, encoding='utf-8', errors='replace') as f:
            text = f.read(4096)
    except OSError:
        return None
    match = re.search(r'^PYTHONDIR = (.+)$', text, re.M)
    if not match:
        return None
    try:
        package = os.path.join(ast.literal_eval(match.group(1)), 'ln_generate')
    except (ValueError, SyntaxError):
        return None
    return package if os.path.isdir(package) else None


def _find_generator(env):
    explicit = env.get('LN_GENERATE')
    if explicit:
        argv = env.subst_list(explicit)[0] if SCons.Util.is_String(explicit) else explicit
        argv = [str(a) for a in argv]
        exe = shutil.which(argv[0]) or argv[0]
        return _Generator(argv, {}, [exe] if os.path.isfile(exe) else [])
    if os.path.isfile(os.path.join(_SOURCE_PACKAGE, '__main__.py')):
        return _Generator([env.subst('$PYTHON'), '-m', 'ln_generate'],
                          {'PYTHONPATH': os.path.dirname(_SOURCE_PACKAGE)},
                          _python_files(_SOURCE_PACKAGE))
    exe = _INSTALLED_EXE if os.path.isfile(_INSTALLED_EXE) else shutil.which('ln_generate')
    if exe:
        package = _launcher_package(exe)
        return _Generator([exe], {}, [exe] + (_python_files(package) if package else []))
    return None


def _generator(env):
    found = _find_generator(env)
    if found is None:
        raise SCons.Errors.UserError(
            f'ln_generate not found: no source checkout next to {__file__}, '
            f'no {_INSTALLED_EXE} and nothing on PATH; set LN_GENERATE')
    return found


def _md_dirs(env):
    dirs = [env.Dir(d).abspath for d in env.Flatten([env.get('LN_MD_DIRS', [])]) if d]
    unique = []
    for d in dirs:
        if d not in unique:
            unique.append(d)
    return unique


def _emitter(target, source, env):
    if len(target) != 1:
        raise SCons.Errors.UserError(
            f'LnGenerate makes exactly one file, got {len(target)} targets')
    lang = env.subst('$LN_LANG') or _SUFFIX_LANG.get(os.path.splitext(str(target[0]))[1])
    if lang not in _LANGS:
        raise SCons.Errors.UserError(f"{target[0]}: set LN_LANG to one of {', '.join(_LANGS)}")
    # Resolved now, while relative directories still mean "relative to this SConscript".
    attrs = target[0].attributes
    attrs.ln_lang = lang
    attrs.ln_md_dirs = _md_dirs(env)
    found = _find_generator(env)
    if found is not None:
        env.Depends(target, found.files)
    return target, source


def _arguments(target, source):
    names = [s.read() if isinstance(s, SCons.Node.Python.Value) else str(s) for s in source]
    attrs = target.attributes
    args = ['--lang', attrs.ln_lang]
    for d in attrs.ln_md_dirs:
        args += ['--md-dir', d]
    return args + names


def _command(target, source, env, for_signature):
    # Literal: paths and names reach the generator verbatim, whatever characters they hold.
    args = ['-o', '$TARGET'] + [SCons.Subst.Literal(a) for a in _arguments(target[0], source)]
    if for_signature:
        # The generator's own files are dependencies; where it lives is not part of it.
        return [['ln_generate'] + args]
    found = _generator(env)
    prefix = []
    if found.extra_env:
        prefix = ['env'] + [f'{k}={v}' for k, v in sorted(found.extra_env.items())]
    return [[SCons.Subst.Literal(a) for a in prefix + found.argv] + args]


def _scan(node, env, path):
    """The md files node's names resolve to, as reported by `ln_generate --print-deps`."""
    found = _find_generator(env)
    if found is None or not node.sources:
        return []
    argv = found.argv + ['-o', node.abspath, '--print-deps'] + _arguments(node, node.sources)
    run_env = {k: str(v) for k, v in env['ENV'].items()}
    run_env.update(found.extra_env)
    try:
        result = subprocess.run(argv, env=run_env, stdin=subprocess.DEVNULL,
                                capture_output=True, text=True, check=False)
    except OSError:
        return []
    if result.returncode != 0:
        # Leave the report to the build step, which runs the same lookup and prints it.
        return []
    return [env.File(line.strip()) for line in result.stdout.splitlines() if line.strip()]


def generate(env):
    env.SetDefault(PYTHON=sys.executable, LN_MD_DIRS=[], LN_LANG='',
                   LN_GENERATE=os.environ.get('LN_GENERATE', ''),
                   LN_GENERATE_COMSTR='')
    action = SCons.Action.Action(_command, '$LN_GENERATE_COMSTR', generator=1)
    env['BUILDERS']['LnGenerate'] = SCons.Builder.Builder(
        action=action,
        emitter=_emitter,
        source_factory=SCons.Node.Python.ValueWithMemo,
        target_scanner=SCons.Scanner.Scanner(_scan, name='LnGenerateScanner'),
        single_source=False,
        # The generator's files are explicit dependencies; no guessing from the command.
        IMPLICIT_COMMAND_DEPENDENCIES=0,
    )


def exists(env):
    return _find_generator(env) is not None
