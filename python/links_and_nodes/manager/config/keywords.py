"""What links_and_nodes does with each keyword of the original Links and Nodes `.lnc`
language: implemented, accepted without effect (its GTK GUI's business, or an opt-out of
something links_and_nodes never does), or refused with the nearest supported
alternative.  Derived from the reader's own tables, so it cannot drift from what the
reader does; docs/configuration.md shows it and a test checks that they agree."""

from __future__ import annotations

from .lexer import SECTION_WORDS
from .process_keys import FLAGS, FLAGS_WITHOUT_EFFECT, IGNORED, LISTS, SCALARS, UNSUPPORTED
from .sections import GroupSection, InstanceSection, NetworkSection

IMPLEMENTED = "implemented"
NO_EFFECT = "accepted, no effect"
REFUSED = "not supported"

# Directives (`include FILE`, `push_name_prefix: X`, ...) the reader carries out.
DIRECTIVES = frozenset({"include", "optional_include", "include_glob",
                        "optional_include_glob", "push_name_prefix", "pop_name_prefix",
                        "add_message_definition_dir", "use_template", "requires_version",
                        "pipe_include"})
PREFIXES = frozenset({"add", "append", "ifdef", "ifndef"})  # `add KEY:`, `ifdef NAME: ...`
CONSTANTS = frozenset({"true", "false"})
# Keys of other sections that the original had and this reader implements.
OTHER_KEYS = (InstanceSection.KEYS | GroupSection.KEYS | NetworkSection.KEYS
              | frozenset({"undef"}))  # `undef: NAME` in a defines section
REFUSED_ELSEWHERE = {"add_process_default_template": "use 'use_template' in each process",
                     **InstanceSection.UNSUPPORTED}


def keyword_status(word: str, category: str) -> tuple[str, str]:
    """(status, note) of a keyword of the original language; `category` is that of its
    vim syntax files: section, key, flag, constant, prefix, or a robotkernel define."""
    if category.startswith("key(") and "define" in category:
        return IMPLEMENTED, "a define of robotkernel's include files, read like any define"
    if category == "flag":
        if word not in FLAGS:
            return REFUSED, "unknown flag"
        if word in FLAGS_WITHOUT_EFFECT:
            return NO_EFFECT, _flag_note(word)
        return IMPLEMENTED, _FLAG_NOTES.get(word, "")
    if category == "constant":
        return (IMPLEMENTED, "boolean value") if word in CONSTANTS else (REFUSED, "")
    if category == "prefix" or word in PREFIXES:
        return (IMPLEMENTED, _PREFIX_NOTES.get(word, "")) if word in PREFIXES else (REFUSED, "")
    if word in SECTION_WORDS or word in DIRECTIVES:
        return IMPLEMENTED, ""
    if word in SCALARS or word in LISTS or word in OTHER_KEYS:
        return IMPLEMENTED, ""
    if word in InstanceSection.IGNORED or word in IGNORED:
        return NO_EFFECT, "GUI setting of the original"
    if word in UNSUPPORTED:
        return REFUSED, UNSUPPORTED[word]
    if word in REFUSED_ELSEWHERE:
        return REFUSED, REFUSED_ELSEWHERE[word]
    return REFUSED, "unknown to links_and_nodes"


_PREFIX_NOTES = {
    "add": "`add KEY: VALUE` extends a list key",
    "append": "`append environment VAR: VALUE` adds to VAR after a ':'",
    "ifdef": "`ifdef NAME: LINE`",
    "ifndef": "`ifndef NAME: LINE`",
}

_FLAG_NOTES = {
    "forward_x11": "the process gets the manager's DISPLAY and XAUTHORITY",
    "no_error_on_stop": "exiting with any status is 'finished', not 'failed'",
    "no_error_on_successful_stop": "always so: exit status 0 is 'finished'",
    "dont_stop_dependent_procs": "its dependents keep running when it stops",
    "start_in_shell": "the command runs under /bin/sh -c",
    "disable_stop": "only a forced stop ends it",
    "no_pty": "output through pipes instead of a pseudo-terminal",
    "set_user_and_home": "always so: USER, LOGNAME and HOME are passed",
}


def _flag_note(word: str) -> str:
    if word in ("no_host_default_templates", "no_default_templates"):
        return "there are no default templates"
    if word == "no_ln_ld_library_path":
        return "LD_LIBRARY_PATH is never changed"
    return "GUI or output display of the original"
