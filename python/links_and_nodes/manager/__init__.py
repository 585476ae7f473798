"""ln_manager: the registry of one links_and_nodes instance.  Clients register themselves
and their topic ports over TCP (docs/protocol.md); the manager checks them, creates and
removes the topics' shared-memory segments and answers with their names.  Topic data
never passes through it.  With a configuration (`ln_manager -c FILE`) it also starts and
supervises the processes of that file through the ln_daemons; `connect()` is the scripting
API for that.  See docs/manager.md and docs/process_management.md."""


def __getattr__(name: str) -> object:
    # The scripting API without importing the manager's server side (or libln) with it.
    if name in ("connect", "Manager", "ManagerError"):
        from ..tools import scripting

        return getattr(scripting, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
