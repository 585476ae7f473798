/* event_internal.h — what the two sides of events (event_handler.c, event_call.c) share:
 * event name rules, the signatures of a handler's service, the reply every handler answers
 * with, and the JSON and hex plumbing of the manager's event commands.  Never installed.
 *
 * A handler of event E is the service "ln_event/E/CLIENT.N" of the event md: its request is
 * the call struct, its response the reply record below, so the layout hash of the event md
 * guards both ends as for any service. */
#ifndef LN_EVENT_INTERNAL_H
#define LN_EVENT_INTERNAL_H

#include <stdint.h>
#include <stdio.h>

#include "svc_internal.h"

/* Service names of handlers start with this, then the event name and "/". */
#define LN_EVENT_SERVICE_PREFIX "ln_event/"

/* The response of a handler's service: has_reply (0/1), then the reply call struct in the
 * signature codec's wire form as a dynamic byte field.  Packed in memory as the codec wants
 * it: u8 at 0, u32 count at 1, pointer at 5. */
#define LN_EVENT_REPLY_SIG "uint8_t 1 1,uint32_t 4 1,uint8_t* 1 1"
#define LN_EVENT_REPLY_SIZE 13

/* LN_OK, or LN_EINVAL (recorded, `what` names the function) for a bad event name. */
int ln_event_check_name(ln_client* clnt, const char* what, const char* event);

/* Parses an event md's "connect|call" signature into its two sections and makes the
 * signature of its handlers' service ("CALL|" LN_EVENT_REPLY_SIG, malloc'd).  LN_EMD (naming
 * the md) or LN_ENOMEM, recorded; on failure nothing is left allocated. */
int ln_event_parse_signature(ln_client* clnt, const char* md_name, const char* signature,
                             ln_sig** connect, ln_sig** call, char** handler_signature);

/* The reply record's fields. */
void ln_event_reply_pack(uint8_t out[LN_EVENT_REPLY_SIZE], int has_reply, uint32_t len,
                         const void* data);
void ln_event_reply_unpack(const uint8_t in[LN_EVENT_REPLY_SIZE], int* has_reply, uint32_t* len,
                           const uint8_t** data);

/* Writes s as a quoted JSON string. */
void ln_event_json_quote(FILE* f, const char* s);
/* Lower-case hex of data[len] into out (2 * len + 1 bytes, NUL-terminated). */
void ln_event_hex(const uint8_t* data, size_t len, char* out);
/* Decodes hex text (even length) into out[*len]; -1 for anything else or if more than
 * `max` bytes. */
int ln_event_unhex(const char* hex, uint8_t* out, size_t max, size_t* len);

#endif /* LN_EVENT_INTERNAL_H */
