/* bell.h — how publishers, the daemon, the manager and libln's own service threads tell a
 * waitset (waitset.c) to look at one of its attachments: a datagram holding the attachment's
 * tag, sent to the waitset's abstract Unix socket "\0ln.bell.<16 hex digits of its id>".
 * Abstract sockets vanish with their process, so a waitset killed by SIGKILL leaves nothing
 * behind; a bell whose waitset is gone is simply refused (ECONNREFUSED).
 *
 * In a ring, reader slot i of a subscriber attached to a waitset holds the bell's id and tag
 * and a `pending` flag, and bit i of the header's `bell_readers` is set.  After every commit
 * (and when the manager changes the publisher count or retires the ring) the writer rings
 * each such reader's bell only if it swaps `pending` from 0 to 1; the waitset swaps it back
 * to 0 (seq_cst) before it looks at the ring, so either it sees the new sample or the writer
 * sees 0 and rings.  A busy waitset therefore costs a writer one atomic exchange, one that
 * keeps up one sendto per sample. */
#ifndef LN_BELL_H
#define LN_BELL_H

#include <stdint.h>
#include <sys/socket.h>
#include <sys/un.h>

#include "ring.h"

/* The address of bell `id` in *addr; returns its length for sendto/bind. */
socklen_t ln_bell_address(uint64_t id, struct sockaddr_un* addr);
/* Sends `tag` to bell `id` (never blocks; a full or vanished bell is ignored). */
void ln_bell_ring(uint64_t id, uint32_t tag);
/* Rings the bell of every reader of the ring registered with one whose `pending` flag was
 * clear (all: after a publisher count change or a retirement, which the waitset looks at
 * whatever the flag says). */
void ln_ring_ring_bells(ln_ring_header* h, int all);
/* Registers reader slot `reader` of the ring with bell `id`/`tag` (id 0: unregisters). */
void ln_ring_set_bell(ln_ring_header* h, uint32_t reader, uint64_t id, uint32_t tag);
/* Clears what a previous subscriber of reader slot `reader` registered (the manager, when it
 * reserves or releases the slot). */
void ln_ring_clear_bell(ln_ring_header* h, uint32_t reader);

#endif /* LN_BELL_H */
