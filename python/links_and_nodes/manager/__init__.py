"""ln_manager: the registry of one links_and_nodes instance.  Clients register themselves
and their topic ports over TCP (docs/protocol.md); the manager checks them, creates and
removes the topics' shared-memory segments and answers with their names.  Topic data
never passes through it.  See docs/manager.md."""
