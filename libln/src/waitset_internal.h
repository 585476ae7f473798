/* waitset_internal.h — what the waitset (waitset.c) needs of the things it waits on, and what
 * they call back when they go away.  Never installed. */
#ifndef LN_WAITSET_INTERNAL_H
#define LN_WAITSET_INTERNAL_H

#include <stdint.h>

#include "ln/ln.h"

/* ---- port.c ---- */
/* LN_OK for a live subscriber handle, else LN_EBADHANDLE (recorded, `what` names the call). */
int ln_inport_check(const ln_inport* p, const char* what);
/* Registers the port with waitset ws as attachment id: its reader slot rings `bell` with the
 * id (bell 0, ws NULL: unregisters).  LN_EINVAL for a subscriber without reader slot. */
int ln_inport_bell(ln_inport* p, ln_waitset* ws, uint32_t id, uint64_t bell);
ln_waitset* ln_inport_waitset(const ln_inport* p);
/* Re-arms the bell, then 1 if a read would find a sample now, 0 if not, < 0 an error. */
int ln_inport_ready(ln_inport* p);
uint64_t ln_inport_write_seq(const ln_inport* p);
/* The topic's publisher count as the port's ring says (< 0: an error). */
int ln_inport_live_publishers(const ln_inport* p);

/* ---- param_block.c ---- */
int ln_param_check_handle(const ln_parameter_block* blk, const char* what);
/* Registers the block with waitset ws as attachment id (ws NULL: unregisters); LN_EBUSY if
 * another waitset has it.  From then on every override handed to the loop rings `bell` with
 * the id. */
int ln_param_bell(ln_parameter_block* blk, ln_waitset* ws, uint32_t id, uint64_t bell);
/* 1 if overrides wait for the block's next update(). */
int ln_param_pending(const ln_parameter_block* blk);

/* ---- svc_group.c / provider.c / event_handler.c ---- */
/* The epoll fd of service group `group` of clnt (readable while requests wait): LN_OK,
 * LN_ENOTFOUND (no such group), LN_EBUSY (a thread pool handles it). */
int ln_svc_group_wait_fd(ln_client* clnt, const char* group, int* fd);
/* The client and group a registered provider / event handler is in (LN_EINVAL if not yet). */
int ln_provider_group_of(const ln_service_provider* prov, ln_client** clnt, const char** group);
int ln_event_handler_provider(const ln_event_handler* handler, ln_service_provider** prov);

/* ---- waitset.c ---- */
/* Called by an attached inport or parameter block (`object`) that is going away: ends its
 * attachment.  ws NULL: nothing to do. */
void ln_waitset_forget(ln_waitset* ws, uint32_t id, const void* object);

#endif /* LN_WAITSET_INTERNAL_H */
