/* svc_tap.h — recording the calls a provider serves (docs/services.md, "Recording calls"): a
 * recorder connects to the provider's socket with TAP instead of HELLO and from then on
 * receives a CALL frame for every completed call.  The handler's thread only copies the call
 * into the tap's bounded queue; a sender thread per provider writes the queues out, and drops
 * (and counts) what does not fit.  Internal.
 *
 * CALL body (little endian): u64 request_time_ns (CLOCK_REALTIME when the request arrived),
 * u64 duration_ns (until the answer was encoded), u64 dropped (calls this tap lost so far),
 * i32 code (0: answered with a response, else the LN_E* code of the error answer), str caller,
 * u32 n + n bytes request (wire form), u32 m + m bytes response (wire form) or error text. */
#ifndef LN_SVC_TAP_H
#define LN_SVC_TAP_H

#include <stddef.h>
#include <stdint.h>

typedef struct ln_service_provider ln_service_provider;
typedef struct ln_service_request ln_service_request;
typedef struct ln_svc_taps ln_svc_taps;

/* Per tap: at most this many queued calls and bytes (one call is taken into an empty queue
 * whatever its size). */
#define LN_SVC_TAP_QUEUE_CALLS 4096
#define LN_SVC_TAP_QUEUE_BYTES ((size_t)8 << 20)

/* The taps of a new provider (none yet): NULL when out of memory. */
ln_svc_taps* ln_svc_taps_new(void);
/* Starts sending calls of `p` to the connected socket `fd` (taken over: closed by the tap).
 * Returns the tap's id (> 0) for ln_svc_tap_hangup, or a negative LN_E* code (fd closed). */
int64_t ln_svc_tap_add(ln_service_provider* p, int fd);
/* The recorder's connection `id` closed: forget the tap and what it had queued. */
void ln_svc_tap_hangup(ln_service_provider* p, int64_t id);
/* Copies one completed call into every tap's queue (call only when p->tapped != 0).
 * code 0: `answer` is the response's wire form, else the error text. */
void ln_svc_tap_call(ln_service_provider* p, const ln_service_request* req, int code,
                     const void* answer, size_t answer_len);
/* Stops the sender thread and frees every tap (the provider is going away). */
void ln_svc_taps_free(ln_service_provider* p);

#endif /* LN_SVC_TAP_H */
