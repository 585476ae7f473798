"""The front ends' share of the command table (tools/commands/): the process commands and
their text views, the event and pull-topic commands, console help and completion, and the
phrases that name a command of a family."""
