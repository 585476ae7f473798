/* default_ports.h — the one home in C and C++ of links_and_nodes' well-known ports and the
 * variables that override them; Python's links_and_nodes.default_ports holds the same numbers
 * (tests/python/naming/test_default_ports.py compares the two).  Internal. */
#ifndef LN_DEFAULT_PORTS_H
#define LN_DEFAULT_PORTS_H

/* ln_daemon's TCP port (the LN "arbiter" port), unless $LN_DAEMON_PORT_ENV says otherwise. */
#define LN_DEFAULT_DAEMON_PORT 54376
#define LN_DAEMON_PORT_ENV "LN_ARBITER_PORT"
/* The data port of topic forwarding: the daemon's TCP port plus this. */
#define LN_DATA_PORT_OFFSET 1
/* The UDP port pull topics are served on (NDN's). */
#define LN_DEFAULT_PULL_PORT 6363

/* A port macro as a string literal, for usage texts: LN_PORT_TEXT(LN_DEFAULT_DAEMON_PORT). */
#define LN_PORT_TEXT_(port) #port
#define LN_PORT_TEXT(port) LN_PORT_TEXT_(port)

#endif /* LN_DEFAULT_PORTS_H */
