"""Client tools of a running system: the client<->manager codec (protocol.py), the scripting
client (scripting.py: connect, Manager, ManagerError), the command table the manager's
features register into and its clients read (commands/), the client side of live
introspection (introspection/) and of parameter blocks (parameters/).  Ordinary clients:
nothing here imports the manager; the manager, the bridges and the recorder import this."""
