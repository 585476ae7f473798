"""SCons helper for the wire schemas (python/links_and_nodes/wire/): runs a generator module
of that package on a schema at build time, with dependencies on the schema, the parser and
the generator, so a changed schema regenerates every codec made from it.

    from ln_wire import wire_generate
    header = wire_generate(env, 'daemon_wire.hpp', 'daemon.schema', 'gen_cpp', '--io x.hpp')
"""

import os
import sys

_WIRE = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), 'python',
                     'links_and_nodes', 'wire')


def wire_generate(env, targets, schema, module, args='', inputs=()):
    """targets (a name or a list; written into the calling SConscript's build directory) from
    the schema file named `schema` (in python/links_and_nodes/wire/) by
    `python -m links_and_nodes.wire.<module> SCHEMA INPUTS... TARGETS... ARGS`; `inputs`
    are further files (nodes or paths) the generator reads."""
    source = os.path.join(_WIRE, schema)
    inputs = [env.File(i) for i in inputs]
    deps = [source] + inputs + [os.path.join(_WIRE, n) for n in ('schema.py', module + '.py')]
    gen_env = env.Clone()
    gen_env['ENV']['PYTHONPATH'] = os.path.dirname(os.path.dirname(_WIRE))
    gen_env['WIRE_PYTHON'] = sys.executable
    named = ''.join(f' ${{SOURCES[{i + 1}]}}' for i in range(len(inputs)))
    command = f'$WIRE_PYTHON -m links_and_nodes.wire.{module} ${{SOURCES[0]}}{named} $TARGETS {args}'
    return gen_env.Command(targets, deps, command)
