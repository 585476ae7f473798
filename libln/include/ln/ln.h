/* ln.h — the public C API of libln, the links_and_nodes client library.
 * This header is the whole contract: everything here is ln_/LN_-prefixed and ABI-stable
 * within one LN_SOVERSION; everything else in libln is internal and not exported. */
#ifndef LN_LN_H
#define LN_LN_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Marks a symbol as part of the ABI; libln is built with -fvisibility=hidden. */
#if defined(__GNUC__) || defined(__clang__)
#define LN_EXPORT __attribute__((visibility("default")))
#else
#define LN_EXPORT
#endif

/* ---- versions ----------------------------------------------------------------------------
 * LN_VERSION_* is the release of the API this header describes.  Within one major version a
 * newer minor only adds to the API, so code built against 0.1 runs with a 0.2 library but
 * not the other way round.  LN_SOVERSION is the ELF soname number (libln.so.1). */
#define LN_VERSION_MAJOR 0
#define LN_VERSION_MINOR 1
#define LN_VERSION_PATCH 0
#define LN_SOVERSION 1

#define LN_STRINGIFY_(x) #x
#define LN_STRINGIFY(x) LN_STRINGIFY_(x)
#define LN_VERSION_STRING                                                                          \
    LN_STRINGIFY(LN_VERSION_MAJOR)                                                                 \
    "." LN_STRINGIFY(LN_VERSION_MINOR) "." LN_STRINGIFY(LN_VERSION_PATCH)

/* ---- errors ------------------------------------------------------------------------------
 * Every libln function that can fail returns LN_OK (0) or one negative code of this table.
 * The table is written once, here; it expands into enum ln_error, ln_strerror(),
 * ln_error_name() and, through the Python bindings, one exception class per entry.
 * Codes are contiguous from -1 downwards and never change meaning once released; new
 * entries are appended at the end. */
#define LN_ERRNO_MAP(XX)                                                                           \
    XX(EINVAL, -1, "invalid argument")                                                             \
    XX(ENOMEM, -2, "out of memory")                                                                \
    XX(ETIMEOUT, -3, "timed out")                                                                  \
    XX(EAGAIN, -4, "operation would block")                                                        \
    XX(ECONNECTION, -5, "manager unreachable or connection lost")                                  \
    XX(EPROTOCOL, -6, "malformed protocol frame")                                                  \
    XX(EVERSION, -7, "protocol or library version mismatch")                                       \
    XX(ELAYOUT, -8, "message layout hash mismatch")                                                \
    XX(ENOTFOUND, -9, "not found")                                                                 \
    XX(EEXIST, -10, "already exists")                                                              \
    XX(ELIMIT, -11, "configured limit reached")                                                    \
    XX(ETOOBIG, -12, "data too big")                                                               \
    XX(ECLOSED, -13, "closed")                                                                     \
    XX(EBUSY, -14, "resource busy")                                                                \
    XX(EOVERRUN, -15, "reader overrun, messages were lost")                                        \
    XX(ESYS, -16, "system call failed")                                                            \
    XX(EPERM, -17, "permission denied")                                                            \
    XX(EMD, -18, "bad message definition")                                                         \
    XX(ESERVICE, -19, "service provider answered with an error")                                   \
    XX(EBADHANDLE, -20, "invalid or destroyed handle")                                             \
    XX(EINTR, -21, "interrupted")                                                                  \
    XX(EREFUSED, -22, "refused by the manager")

enum ln_error {
    LN_OK = 0,
#define LN_ERRNO_ENUM_(name, code, message) LN_##name = (code),
    LN_ERRNO_MAP(LN_ERRNO_ENUM_)
#undef LN_ERRNO_ENUM_
};

/* Human-readable text for a code: never NULL, "unknown error" for codes not in the table.
 * The string is static; the caller must not free it. */
LN_EXPORT const char* ln_strerror(int code);

/* Table name of a code without the LN_ prefix ("ETIMEOUT"; "OK" for LN_OK), or NULL for a
 * code not in the table.  The string is static. */
LN_EXPORT const char* ln_error_name(int code);

/* Number of error entries in the table (LN_OK not counted).  Their codes are exactly
 * -1 .. -ln_error_count(), which lets bindings enumerate the table at run time. */
LN_EXPORT int ln_error_count(void);

/* Version of the running library as "MAJOR.MINOR.PATCH".  The string is static. */
LN_EXPORT const char* ln_version(void);

/* LN_OK if the running library can serve a caller built against API major.minor (same
 * major, library minor >= minor), LN_EVERSION if not, LN_EINVAL for negative numbers.
 * Call it as LN_VERSION_CHECK() to pass the numbers of the header you compiled against. */
LN_EXPORT int ln_version_check(int major, int minor);
#define LN_VERSION_CHECK() ln_version_check(LN_VERSION_MAJOR, LN_VERSION_MINOR)

/* ==== clients, topics ======================================================================
 * Ownership: a client owns its ports; ln_client_destroy() closes every port it still has, so
 * port handles must not be used after their client is gone.  Setup calls (create, publish,
 * subscribe, unpublish, unsubscribe, destroy) must come from one thread at a time; ln_write,
 * ln_read and the zero-copy calls may be used from any thread, one thread per port at a time.
 * Timeouts are in seconds: < 0 (or infinity) waits forever, 0 does not wait (LN_EAGAIN), > 0
 * waits at most that long (LN_ETIMEOUT), NaN is LN_EINVAL.  A port must not be used after it
 * was closed or its client destroyed. */
typedef struct ln_client ln_client;
typedef struct ln_outport ln_outport;
typedef struct ln_inport ln_inport;

/* Reconnection (docs/manager.md, "A manager restarted under running clients"): a client
 * watches its manager connection from a background thread; when the manager goes away it
 * reconnects with back-off (50 ms doubling to 1 s) and re-registers every port and service
 * provider it holds.  Meanwhile manager requests fail with LN_ECONNECTION; ln_write/ln_read
 * never notice.  LN_CLIENT_NO_RECONNECT in ln_client_options.flags, or LN_RECONNECT=0 in the
 * environment, turns it off: then a lost connection stays lost, as for a client of 0.1. */
#define LN_CLIENT_NO_RECONNECT 0x1u

typedef struct ln_client_options {
    const char* manager; /* "HOST:PORT" or ":PORT"; NULL: -ln_manager in argv, then $LN_MANAGER */
    int argc;            /* argv to search for "-ln_manager HOST:PORT" (may be 0/NULL) */
    char** argv;
    double timeout; /* seconds for connecting and for each manager request (default 10) */
    uint32_t flags; /* LN_CLIENT_* (default 0: reconnect) */
} ln_client_options;

LN_EXPORT void ln_client_options_init(ln_client_options* opts);

/* Connects to the manager and registers as `name` (LN_PROGRAM_NAME overrides it; the manager
 * may append "-2", "-3", ... if the name is taken).  On success *out owns the connection; free
 * it with ln_client_destroy().  On failure *out is NULL and the code says why (ECONNECTION,
 * EVERSION, EPROTOCOL, ETIMEOUT, EINVAL); ln_last_error() has the details. */
LN_EXPORT int ln_client_create(ln_client** out, const char* name, const ln_client_options* opts);
LN_EXPORT int ln_client_destroy(ln_client* clnt);
/* The name the manager gave this client; owned by the client. */
LN_EXPORT const char* ln_client_name(const ln_client* clnt);

/* Text of the last error of the calling thread, with context (topic, md, sizes, errno).
 * Valid until the thread's next libln call that fails; never NULL. */
LN_EXPORT const char* ln_last_error(void);

/* The last error of any call on this client or its ports, from whichever thread: copies its
 * text into text[size] (NUL-terminated, may be NULL/0) and returns its code (LN_OK if none). */
LN_EXPORT int ln_client_last_error(const ln_client* clnt, char* text, size_t size);

/* Port options: buffers = 1 is a *latest* subscriber (always the newest sample), N > 1 a
 * *queued* one that sees every sample while it is at most N sequence numbers behind (older
 * ones are dropped and counted as overruns; on a host that gets the topic from another one,
 * numbers lost on the network count like dropped samples).  For publishers,
 * LN_PUBLISH_WAIT_FOR_SUBSCRIBERS makes ln_write wait (up to its timeout) while a queued
 * subscriber has no free buffer, instead of dropping that subscriber's oldest sample. */
#define LN_PUBLISH_WAIT_FOR_SUBSCRIBERS 0x1u
/* Subscribers: how samples reach this subscriber's host when the publisher runs on another
 * one (docs/network.md).  Neither bit: the topic's setting in the .lnc, else UDP.  A host
 * gets a topic over TCP when any of its subscriptions (or the .lnc) asks for it.  Both bits,
 * an LN_SUBSCRIBE_* bit on a publisher or LN_PUBLISH_* on a subscriber: LN_EINVAL. */
#define LN_SUBSCRIBE_UDP 0x100u /* newest sample wins; lost datagrams are not repeated */
#define LN_SUBSCRIBE_TCP 0x200u /* every sample, in order (bounded queue, drops counted) */
/* Before a blocking read sleeps, it polls (yielding the CPU) for up to spin_us: a sample that
 * comes within that time is seen without a futex wake-up, which costs tens of microseconds when
 * it crosses CPUs.  0 sleeps at once; the cost is at most spin_us of CPU per blocking read that
 * waits longer.  A publisher with LN_PUBLISH_WAIT_FOR_SUBSCRIBERS polls the same way before it
 * sleeps for a free buffer (then the subscriber's release makes no system call). */
#define LN_DEFAULT_SPIN_US 20u
typedef struct ln_port_options {
    uint32_t buffers; /* 1 .. 1024, default 1 */
    uint32_t flags;   /* publishers: LN_PUBLISH_*; subscribers: at most one LN_SUBSCRIBE_* */
    uint32_t spin_us; /* poll before sleeping (subscribers: for a sample; waiting publishers:
                         for a free buffer), default LN_DEFAULT_SPIN_US */
} ln_port_options;

LN_EXPORT void ln_port_options_init(ln_port_options* opts);

/* Register a publisher/subscriber of `topic` with messages of md `md_name`, layout hash and
 * size (generated headers give all three as NAME_MD, e.g. ROBOT_JOINT_STATE_MD).  A topic has
 * one layout: a port with another hash or size is refused with LN_ELAYOUT.  opts may be NULL.
 * The port belongs to the client; close it with ln_unpublish/ln_unsubscribe or let
 * ln_client_destroy do it. */
LN_EXPORT int ln_publish(ln_client* clnt, ln_outport** out, const char* topic, const char* md_name,
                         uint64_t layout_hash, size_t message_size, const ln_port_options* opts);
LN_EXPORT int ln_subscribe(ln_client* clnt, ln_inport** out, const char* topic, const char* md_name,
                           uint64_t layout_hash, size_t message_size, const ln_port_options* opts);
LN_EXPORT int ln_unpublish(ln_outport* port);
LN_EXPORT int ln_unsubscribe(ln_inport* port);

/* What a read returns besides the data. */
typedef struct ln_sample_info {
    uint64_t seq;         /* publish sequence number of the topic, from 1; gap-free on the
                            * publisher's host, on other hosts samples lost on the network
                            * leave gaps (a queued port counts them in overruns) */
    int64_t timestamp_ns; /* CLOCK_REALTIME when it was published */
    uint64_t overruns;    /* samples this port lost since its previous read */
} ln_sample_info;

/* Copy `size` bytes (must equal the message size) into the topic.  Never blocks unless the
 * port has LN_PUBLISH_WAIT_FOR_SUBSCRIBERS or another publisher of the topic holds a loan. */
LN_EXPORT int ln_write(ln_outport* port, const void* data, size_t size, double timeout);
/* Zero-copy write: *data points at the next slot; fill it, then commit (publishes it) or
 * abort (publishes nothing), on the same thread.  Other publishers of the topic wait until
 * then; from another thread commit and abort fail with LN_EBUSY. */
LN_EXPORT int ln_write_loan(ln_outport* port, void** data, double timeout);
LN_EXPORT int ln_write_commit(ln_outport* port);
LN_EXPORT int ln_write_abort(ln_outport* port);

/* Copy the next sample (latest: the newest one not read yet; queued: the oldest unread) into
 * data[size].  info may be NULL.  A sample is never torn: a slot overwritten while being
 * copied is detected and skipped (counted in overruns). */
LN_EXPORT int ln_read(ln_inport* port, void* data, size_t size, double timeout,
                      ln_sample_info* info);
/* Zero-copy read: *data points into the ring until ln_read_release(), which returns LN_OK if
 * the sample stayed intact, LN_EOVERRUN if a publisher overwrote it meanwhile (the ring wrapped
 * around: use more buffers or release sooner). */
LN_EXPORT int ln_read_borrow(ln_inport* port, const void** data, double timeout,
                             ln_sample_info* info);
LN_EXPORT int ln_read_release(ln_inport* port);

/* Blocking reads and signals: by default a blocking ln_read / ln_read_borrow sleeps on after
 * a signal handler ran.  After ln_inport_set_interruptible(port, 1) it returns LN_EINTR then
 * (as read(2) without SA_RESTART), so that a language runtime can run its handlers (Python's
 * Ctrl-C).  ln_inport_interrupt, from any thread, makes the port's blocking read that sleeps
 * now, or else its next one, return LN_EINTR at once (a runtime closing the port from another
 * thread wakes its reader first). */
LN_EXPORT int ln_inport_set_interruptible(ln_inport* port, int on);
LN_EXPORT int ln_inport_interrupt(ln_inport* port);

LN_EXPORT int ln_outport_subscriber_count(const ln_outport* port);
LN_EXPORT int ln_inport_publisher_count(const ln_inport* port);
/* Total samples this subscriber lost since it subscribed. */
LN_EXPORT uint64_t ln_inport_overruns(const ln_inport* port);

/* ---- time ----
 * ln_now gives the time a program should act on, in ns since the epoch: CLOCK_REALTIME, or,
 * after ln_client_use_clock, the replay time of the ln_play --clock publishing on `topic`
 * (NULL: "ln.clock"; md ln/clock; docs/recording.md, "Replay control and the replay clock").
 * Then it is the newest clock sample extrapolated with its rate (using CLOCK_REALTIME since
 * the sample's stamp) while not paused, and exactly the sample's time while paused; within
 * one clock epoch (no pause, seek or rate change between) it never decreases.  Before the
 * first clock sample it is 0 (as ROS's time), LN_OK all the same.  ln_now never blocks and
 * never allocates, and may be called from any thread.  use_clock is a setup call: the
 * subscription belongs to the client; LN_EEXIST if it follows another clock topic already
 * (the same one: LN_OK). */
LN_EXPORT int ln_client_use_clock(ln_client* clnt, const char* topic);
LN_EXPORT int ln_now(ln_client* clnt, int64_t* ns);

/* ==== services ==============================================================================
 * A service is a named request/response call typed by a service md (docs/services.md).  The
 * provider registers it with the manager and serves it on its own sockets: a Unix domain socket
 * for callers on its host, TCP for the others.  Callers look it up in the manager once and then
 * talk to the provider directly, over a connection kept open between calls.
 *
 * Both sides pass the service md as name, layout hash and signature; generated headers give the
 * three as NAME_SERVICE (e.g. ROBOT_SET_GAINS_SERVICE).  Request and response are the generated
 * `..._request_t` / `..._response_t` structs; a dynamic field is its `_len` count plus a pointer
 * to that many packed elements.  Requests and responses travel in a pointer-free wire form
 * checked against the signature: every length is checked before anything is allocated, and a
 * message longer than the maximum size (default LN_SERVICE_DEFAULT_MAX_SIZE) is refused with
 * LN_ETOOBIG. */
typedef struct ln_service ln_service;                   /* the caller's handle */
typedef struct ln_service_provider ln_service_provider; /* the provider's handle */
typedef struct ln_service_request ln_service_request;   /* one call, inside a handler */

#define LN_SERVICE_DEFAULT_MAX_SIZE ((size_t)16 << 20)

/* ---- callers ----
 * ln_get_service makes a handle without contacting anyone; the first call looks the service up
 * and connects.  ln_service_call sends *request (the struct of the request section) and fills
 * *response; dynamic fields of the response point into memory of the handle, valid until the
 * next call on it or ln_service_release.  One call at a time per handle (concurrent calls on
 * one handle are serialized); use one handle per thread for parallel calls.  Errors:
 *   LN_ESERVICE   the provider answered with an error: ln_last_error() has its text;
 *   LN_ENOTFOUND  nobody provides the service; LN_ELAYOUT: provided with another layout;
 *   LN_ECONNECTION the provider could not be reached or closed the connection during the call
 *                 (the call may or may not have been executed);
 *   LN_ETIMEOUT   no response within `timeout` seconds (the connection is dropped, so a late
 *                 response can never be taken for the next call's);
 *   LN_ETOOBIG / LN_EINVAL  the request cannot be encoded (too big, NULL dynamic pointer);
 *   LN_EPROTOCOL  the provider's response is malformed.
 * After any error the next call starts afresh: it looks the service up again and reconnects,
 * so a restarted provider is found by itself. */
LN_EXPORT int ln_get_service(ln_client* clnt, ln_service** out, const char* name,
                             const char* md_name, uint64_t layout_hash, const char* signature);
LN_EXPORT int ln_service_call(ln_service* svc, const void* request, void* response, double timeout);
/* Largest message (wire bytes and decoded dynamic data) this caller encodes as a request or
 * accepts as a response. */
LN_EXPORT int ln_service_set_max_size(ln_service* svc, size_t max_bytes);
/* Closes the connection and frees the handle (ln_client_destroy releases the remaining ones). */
LN_EXPORT int ln_service_release(ln_service* svc);

/* ---- providers ----
 * ln_get_service_provider makes a provider; set its handler, then ln_service_provider_register
 * it in a group (NULL or "" is the default group): that opens its sockets and registers it with
 * the manager.  Requests of a group are handled by whichever thread calls
 * ln_wait_and_handle_service_group_requests for it, or by the threads of a pool after
 * ln_handle_service_group_in_thread_pool.
 *
 * The handler runs once per request.  It reads the request with ln_service_request_get_data,
 * then answers with ln_service_request_respond (a response struct; it is encoded at once, so
 * its dynamic data may live on the handler's stack) or ln_service_request_respond_error (a text
 * the caller gets with LN_ESERVICE), and returns 0.  A handler that returns without answering
 * answers an error: the text of its negative return code (and of ln_last_error() if that is
 * about this call), or "handler returned without responding" for 0.  Requests that cannot be
 * decoded (malformed, too big, another layout) are answered with an error and never reach the
 * handler; the provider keeps serving every other caller. */
typedef int (*ln_service_handler)(ln_client* clnt, ln_service_request* req, void* user_data);

LN_EXPORT int ln_get_service_provider(ln_client* clnt, ln_service_provider** out, const char* name,
                                      const char* md_name, uint64_t layout_hash,
                                      const char* signature);
LN_EXPORT int ln_service_provider_set_handler(ln_service_provider* provider,
                                              ln_service_handler handler, void* user_data);
/* Largest message (wire bytes and decoded dynamic data) this provider accepts as a request or
 * encodes as a response; set it before registering. */
LN_EXPORT int ln_service_provider_set_max_size(ln_service_provider* provider, size_t max_bytes);
LN_EXPORT int ln_service_provider_register(ln_service_provider* provider, const char* group);
/* Unregisters the service, closes its sockets and connections and frees the handle.  Waits for
 * a handler of it that is running in another thread; from inside one of its own handlers it
 * fails with LN_EBUSY. */
LN_EXPORT int ln_unregister_service_provider(ln_service_provider* provider);

/* Handle the requests of `group` that arrive within `timeout` seconds: waits for the first one,
 * then handles every request that is ready without waiting again.  Returns how many requests
 * were handled (0 when the timeout passed without any), or an error: LN_ENOTFOUND for a group
 * with no registered provider, LN_EBUSY if a thread pool handles the group. */
LN_EXPORT int ln_wait_and_handle_service_group_requests(ln_client* clnt, const char* group,
                                                        double timeout);
/* Hand `group` to the thread pool `pool` (created on first use with one thread): from now on
 * its threads handle the group's requests, concurrently up to the pool's maximum number of
 * threads.  The pool stops when the client is destroyed. */
LN_EXPORT int ln_handle_service_group_in_thread_pool(ln_client* clnt, const char* group,
                                                     const char* pool);
/* Maximum number of threads of `pool` (1 .. 256; creates the pool if it does not exist yet). */
LN_EXPORT int ln_set_max_threads(ln_client* clnt, const char* pool, unsigned max_threads);

/* ---- inside a handler ---- */
/* Fills *request (the request struct) with the call's request; dynamic fields point into memory
 * of the call, valid until the handler returns. */
LN_EXPORT int ln_service_request_get_data(ln_service_request* req, void* request);
LN_EXPORT int ln_service_request_respond(ln_service_request* req, const void* response);
LN_EXPORT int ln_service_request_respond_error(ln_service_request* req, const char* text);
/* Name of the service being called (owned by the provider). */
LN_EXPORT const char* ln_service_request_service_name(const ln_service_request* req);

/* ==== events (docs/events.md) ==============================================================
 * An event is a named one-to-many call typed by an event md (sections `connect` and `call`):
 * any number of clients *connect* a handler to event "robot.faults", each stating its connect
 * struct (e.g. a minimum severity); any client *calls* the event with a call struct, which
 * goes to every handler connected at that moment, in parallel.  Each handler may answer with
 * a reply (a struct of the call section) or an error.  Nothing is queued: a call while no
 * handler is connected reaches nobody and returns 0.
 *
 * A handler is a service provider named "ln_event/EVENT/CLIENT.N" whose request is the call
 * struct, registered in a service group like any provider (its calls are handled by
 * ln_wait_and_handle_service_group_requests or a thread pool of that group); the manager keeps
 * its connect struct.  Both are registered again after a manager restart.  Generated headers
 * give the md as NAME_EVENT (md name, layout hash, signature "connect|call"). */
typedef struct ln_event ln_event;                 /* a caller's handle */
typedef struct ln_event_handler ln_event_handler; /* a connected handler */
typedef struct ln_event_request ln_event_request; /* one call, inside a handler */

#define LN_EVENT_MAX_NAME 160          /* bytes of an event name */
#define LN_EVENT_MAX_CONNECT_SIZE 1024 /* bytes of a connect struct in wire form */
#define LN_EVENT_MAX_HANDLERS 256      /* handlers connected to one event */

/* Runs once per call on the thread that handles the group.  It reads the call with
 * ln_event_request_get_data and may answer with ln_event_request_reply (a call struct; encoded
 * at once) or ln_event_request_reply_error (the caller's result for this handler gets
 * LN_ESERVICE and the text).  Returning 0 without answering delivers the call without a
 * reply; a negative return answers an error with the text of that code. */
typedef int (*ln_event_handler_fn)(ln_client* clnt, ln_event_request* call, void* user_data);

/* Connect `handler` to event `event` (1..LN_EVENT_MAX_NAME bytes of A-Z a-z 0-9 _ . : / -,
 * not starting with '.'), stating *connect (the struct of the connect section; NULL only if
 * that section is empty).  It is registered in service group `group` (NULL: the default) and
 * receives calls once this returns.  All handlers of an event use one layout: another one is
 * refused with LN_ELAYOUT; more than LN_EVENT_MAX_HANDLERS with LN_ELIMIT; a connect struct
 * over LN_EVENT_MAX_CONNECT_SIZE wire bytes with LN_ETOOBIG.  ln_client_destroy disconnects
 * the handlers a client still has. */
LN_EXPORT int ln_event_connect(ln_client* clnt, ln_event_handler** out, const char* event,
                               const char* md_name, uint64_t layout_hash, const char* signature,
                               const void* connect, ln_event_handler_fn handler, void* user_data,
                               const char* group);
/* Unregisters the handler and frees it; waits for a call of it running in another thread,
 * LN_EBUSY from inside its own handler. */
LN_EXPORT int ln_event_disconnect(ln_event_handler* handler);
/* The handler's service name, "ln_event/EVENT/CLIENT.N" (owned by the handler). */
LN_EXPORT const char* ln_event_handler_name(const ln_event_handler* handler);

/* Inside a handler: the call struct (dynamic fields point into memory of the call, valid until
 * the handler returns), an answer, and the name of the event. */
LN_EXPORT int ln_event_request_get_data(ln_event_request* call, void* data);
LN_EXPORT int ln_event_request_reply(ln_event_request* call, const void* reply);
LN_EXPORT int ln_event_request_reply_error(ln_event_request* call, const char* text);
LN_EXPORT const char* ln_event_request_event_name(const ln_event_request* call);

/* ---- callers ----
 * ln_get_event makes a handle without contacting anyone.  ln_event_call asks the manager which
 * handlers are connected, skips those the filter (if set) declines, sends *call to all the
 * others at once and then waits, up to `timeout` seconds in all (< 0: forever), for their
 * answers.  It returns how many handlers received the call and answered without error (0 if
 * none is connected: not an error), or an error of the call as a whole: LN_ELAYOUT (the
 * handlers use another layout; the text names both mds), LN_EINVAL (bad arguments, a call
 * struct that cannot be encoded), LN_ECONNECTION (the manager is unreachable and this handle
 * has never seen the handler list; once it has, the last list is used instead), or what the
 * filter returned.  What happened at each handler is in its result. */
typedef struct ln_event_result {
    const char* handler; /* the handler's service name */
    const char* client;  /* the name of the client that connected it */
    int code;            /* LN_OK: received; else why not (LN_ESERVICE: answered an error,
                          * LN_ECONNECTION: died or unreachable, LN_ETIMEOUT, ...) */
    const char* error;   /* the text for code != LN_OK, "" otherwise */
    const void* connect; /* its connect struct */
    const void* reply;   /* its reply (a call struct), NULL if it sent none */
} ln_event_result;

/* Decides per handler before anything is sent: > 0 call it, 0 skip it, < 0 abort the whole
 * call with that code (nothing is sent). */
typedef int (*ln_event_filter)(const void* connect, void* user_data);

LN_EXPORT int ln_get_event(ln_client* clnt, ln_event** out, const char* event, const char* md_name,
                           uint64_t layout_hash, const char* signature);
LN_EXPORT int ln_event_set_filter(ln_event* ev, ln_event_filter filter, void* user_data);
LN_EXPORT int ln_event_call(ln_event* ev, const void* call, double timeout);
/* The results of the last call, one per handler it was sent to, ordered by handler name; they
 * (and the memory they point to) stay valid until the next call or ln_event_release. */
LN_EXPORT int ln_event_result_count(const ln_event* ev);
LN_EXPORT int ln_event_get_result(const ln_event* ev, size_t index, ln_event_result* out);
LN_EXPORT int ln_event_release(ln_event* ev);

/* ==== manager commands and topic loggers (docs/logging.md) ================================
 * ln_control sends one control command, a JSON object with a string "op" (docs/protocol.md,
 * "Control"), on the client's manager connection and waits (up to the client's timeout) for
 * the answer.  LN_OK: *result is the answer's JSON text, which the caller frees with
 * ln_free; result may be NULL if the text is not wanted.  A command the manager refuses is
 * LN_EREFUSED (or the code its answer names) with the manager's reason as ln_last_error().
 * Thread-safe like every client request. */
LN_EXPORT int ln_control(ln_client* clnt, const char* command, char** result);
/* Frees memory libln handed out (ln_control's result).  NULL is fine. */
LN_EXPORT void ln_free(void* p);

/* A logger keeps the last samples of its topics in memory on their publishers' hosts (in
 * ln_daemon, never slowing the publisher), from enable to disable; the manager merges and
 * saves them.  The handle names a logger of the manager: ln_logger_open creates it there
 * if it does not exist, ln_logger_close frees only the handle.  Every call is one request
 * to the manager; errors as for ln_control (e.g. LN_ELIMIT: over the daemon's logger
 * memory; LN_ENOTFOUND). */
typedef struct ln_logger ln_logger;
LN_EXPORT int ln_logger_open(ln_client* clnt, const char* name, ln_logger** out);
/* Log topic (a name or an fnmatch pattern) `depth` samples deep (>= 1), keeping the samples
 * whose sequence number is a multiple of `divisor` (>= 1), none older than `span` seconds
 * before the newest (0: no limit). */
LN_EXPORT int ln_logger_add_topic(ln_logger* lg, const char* topic, uint32_t depth,
                                  uint32_t divisor, double span);
/* Start a new capture (what the logger held is cleared) / stop it, keeping what it has. */
LN_EXPORT int ln_logger_enable(ln_logger* lg);
LN_EXPORT int ln_logger_disable(ln_logger* lg);
/* Fetch every host's samples and write them, merged in publish order, to `path` on the
 * manager's host: MCAP for *.mcap (samples in the default encoding, ros2/CDR, as MCAP
 * viewers decode; a topic ros2 cannot carry stays raw ln bytes), numpy arrays for *.npz. */
LN_EXPORT int ln_logger_save(ln_logger* lg, const char* path);
LN_EXPORT void ln_logger_close(ln_logger* lg);

/* ==== client logging (docs/logging.md, "Client logging") ==================================
 * Log lines with a level, the time, file:line and the text, collected by the manager from
 * every client (`ln_manager log`, the web UI's log page, `ln_record --logs`).  A call copies
 * the format and its arguments (strings too) into a slot of a bounded queue of the client (no
 * lock, no system call, never waits); a thread of the client formats them (printf's rules)
 * and sends the queue to the manager in batches on the client's connection.  Formats with
 * %n, %L, %ls/%lc, positional or more than 16 arguments are formatted at once instead.  When the queue is full the line is dropped and counted (ln_log_counts; the
 * manager shows the count per client).  The queue and its thread start with the first line
 * and end with the client (ln_client_destroy sends what is queued first, waiting at most the
 * client's timeout).  Texts longer than LN_LOG_TEXT_MAX - 1 bytes are cut; bytes that are
 * not UTF-8 become '?'. */
#define LN_LOG_DEBUG 10 /* the numbers of Python's logging levels */
#define LN_LOG_INFO 20
#define LN_LOG_WARNING 30
#define LN_LOG_ERROR 40
#define LN_LOG_CRITICAL 50
#define LN_LOG_TEXT_MAX 512 /* bytes of one line's text, NUL included */
#define LN_LOG_QUEUE 1024   /* lines a client's queue holds */

/* LN_OK (queued), LN_EAGAIN (the queue is full: dropped and counted), LN_EINVAL (a level
 * outside LN_LOG_DEBUG..LN_LOG_CRITICAL or fmt NULL), LN_EBADHANDLE; a line below the
 * client's level (ln_log_set_level) is LN_OK and not sent.  Thread-safe. */
LN_EXPORT int ln_log(ln_client* clnt, int level, const char* fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* The same with where it was logged: `file` (NULL: none) and `line`. */
LN_EXPORT int ln_log_at(ln_client* clnt, int level, const char* file, int line, const char* fmt,
                        ...) __attribute__((format(printf, 5, 6)));
/* For bindings: a ready text (no formatting) and the name of the logger it came from (Python's
 * logger name; NULL or "": none). */
LN_EXPORT int ln_log_text(ln_client* clnt, int level, const char* file, int line,
                          const char* logger, const char* text);
/* `LN_LOG(clnt, LN_LOG_WARNING, "speed %g", v)`: ln_log_at with __FILE__ and __LINE__. */
#define LN_LOG(clnt, level, ...) ln_log_at((clnt), (level), __FILE__, __LINE__, __VA_ARGS__)
/* Lines below `level` are not sent (default LN_LOG_DEBUG: all). */
LN_EXPORT int ln_log_set_level(ln_client* clnt, int level);
/* Lines queued so far and lines dropped so far (the queue was full, or the manager could
 * not be reached when they were sent); either pointer may be NULL. */
LN_EXPORT int ln_log_counts(ln_client* clnt, uint64_t* queued, uint64_t* dropped);
/* Wait until every line queued before the call has been sent (or dropped): LN_OK, or
 * LN_ETIMEOUT after `timeout` seconds (< 0: forever).  Not for the fast path: it waits. */
LN_EXPORT int ln_log_flush(ln_client* clnt, double timeout);

/* ==== parameter blocks (docs/parameters.md) ================================================
 * A block is a named set of typed parameters of one client.  Each parameter has an input
 * (a variable of the program, or none: then its default) and an output the program uses; the
 * manager's tools (ln_manager param ..., the console, the scripting API) may override the
 * output.  An override is checked (type, element count, range, read-only, the program's
 * validator) on libln's own service thread and becomes visible at the program's next
 * ln_parameter_block_update(), all overrides of one request together.  update() takes no
 * lock, makes no system call and allocates nothing: call it from the real-time loop.
 *
 * The block is served as service "<client name>.parameters.<block>" (md ln/parameters/query)
 * in service group "ln.parameters", handled by the client's thread pool "ln.parameters";
 * a manager restart changes nothing (the client registers it again, values and overrides
 * live in the program).  Initial overrides come from $LN_PARAMETERS (the manager sets it
 * from the process's `parameters:` in the .lnc).  Setup (create, add, set_validator,
 * register, destroy) from one thread; update() and changed() from the loop's thread. */
typedef struct ln_parameter_block ln_parameter_block;

#define LN_PARAMETER_MIN 0x1u       /* desc.min is checked: every element >= min */
#define LN_PARAMETER_MAX 0x2u       /* desc.max is checked: every element <= max */
#define LN_PARAMETER_READ_ONLY 0x4u /* shown by the tools, never overridden */
#define LN_PARAMETER_MAX_NAME 63    /* bytes of a block or parameter name */

typedef struct ln_parameter_desc {
    const char* name;        /* 1..LN_PARAMETER_MAX_NAME bytes of A-Z a-z 0-9 _ . - */
    const char* type;        /* an md primitive: char, int8_t .. uint64_t, float, double
                              * (and the md aliases int, short, float32_t, float64_t) */
    uint32_t count;          /* elements (0 counts as 1); char[count] holds a string */
    uint32_t flags;          /* LN_PARAMETER_* */
    const char* description; /* may be NULL */
    const void* input;       /* count elements the program writes, or NULL: the value
                              * without an override is then *output as it was at add() */
    void* output;            /* count elements update() writes; required */
    double min, max;         /* with LN_PARAMETER_MIN / _MAX (not for char) */
} ln_parameter_desc;

/* Called on the service thread for every value about to be taken (after the type, count,
 * range and read-only checks): return 0 to accept it, anything else to refuse it, with a
 * reason written into reason[reason_size] (NUL-terminated) that the setter receives.
 * `value` holds count elements of the parameter's type.  For the initial overrides it runs
 * on the thread calling register. */
typedef int (*ln_parameter_validator)(ln_parameter_block* blk, int index, const char* name,
                                      const void* value, char* reason, size_t reason_size,
                                      void* user_data);

/* A block `name` (1..LN_PARAMETER_MAX_NAME bytes of A-Z a-z 0-9 _ -) of the client; nothing
 * is registered yet.  ln_client_destroy destroys the blocks the client still has. */
LN_EXPORT int ln_parameter_block_create(ln_client* clnt, ln_parameter_block** out,
                                        const char* name);
/* Adds a parameter (before register); returns its index (>= 0) or LN_EINVAL, LN_EEXIST,
 * LN_EBUSY (registered already), LN_ELIMIT.  The strings of *desc are copied; input and
 * output are kept and must stay valid while the block exists. */
LN_EXPORT int ln_parameter_block_add(ln_parameter_block* blk, const ln_parameter_desc* desc);
LN_EXPORT int ln_parameter_block_set_validator(ln_parameter_block* blk,
                                               ln_parameter_validator validator, void* user_data);
/* Takes the initial overrides of $LN_PARAMETERS (those it refuses are printed on stderr and
 * listed by the tools) and registers the block's service.  From now on overrides may come.
 * After a failure (e.g. LN_ECONNECTION) it may be called again; LN_EBUSY once registered. */
LN_EXPORT int ln_parameter_block_register(ln_parameter_block* blk);
/* The loop's update point: takes the overrides that arrived since the last call, then writes
 * every output (the override, else the input; a parameter without input only when its value
 * changed).  Returns how many parameters changed their override (set or reset) since the last
 * call, 0 mostly; LN_EBADHANDLE for a bad handle. */
LN_EXPORT int ln_parameter_block_update(ln_parameter_block* blk);
/* 1 if parameter `index` changed in the last update(), 0 if not, < 0 for a bad argument. */
LN_EXPORT int ln_parameter_block_changed(const ln_parameter_block* blk, int index);
/* The service name "<client>.parameters.<block>" (owned by the block). */
LN_EXPORT const char* ln_parameter_block_service_name(const ln_parameter_block* blk);
/* Unregisters the service (waiting for a request being handled) and frees the block. */
LN_EXPORT int ln_parameter_block_destroy(ln_parameter_block* blk);

/* ==== waiting on many things: the waitset (docs/waiting.md) =================================
 * A waitset lets one thread wait for whatever comes first of: samples on inports, the
 * deadline of an inport ("no sample for X seconds"), an inport's topic losing its last
 * publisher or getting one again, requests of a service group, overrides for a parameter
 * block, file descriptors, interval timers, and ln_waitset_trigger from another thread.
 * ln_waitset_wait sleeps in one kernel wait (epoll) until one of them fires and reports each
 * as an ln_waitset_event; it never polls and never allocates.
 *
 * Publishers (and the daemon injecting forwarded samples, and the manager changing publisher
 * counts) notify a waitset through a datagram to its abstract Unix socket, only when it has
 * looked at that inport since the last notification: a waitset that keeps up costs a
 * publisher one system call per sample, one that is busy costs nothing.  Wake-ups therefore
 * reach waitsets in the publisher's network namespace (on a host, as ln_host_id says).
 *
 * Reports are level-triggered for data: an inport with unread samples is reported by every
 * wait until they are read.  Deadline, GONE/BACK and timers are edges: reported once each
 * time they happen.  Events that do not fit into ready[] stay pending for the next wait.
 *
 * Threads: wait (and the reads of attached inports, which the wait may move to a grown ring)
 * from one thread at a time; attach, detach, trigger from any thread, also while another one
 * waits (it wakes and takes the change into account).  An inport or parameter block is
 * attached to at most one waitset; destroy the waitset (or detach) before closing what is
 * attached, except that closing an inport or ending its client detaches nothing in shared
 * memory that could harm anyone (the manager reuses the reader slot cleanly). */
typedef struct ln_waitset ln_waitset;

/* What fired (ln_waitset_event.kind). */
enum ln_waitset_kind {
    LN_WAIT_DATA = 1,       /* the inport has a sample to read */
    LN_WAIT_DEADLINE = 2,   /* the inport had no new sample for its deadline */
    LN_WAIT_GONE = 3,       /* the inport's topic lost its last publisher */
    LN_WAIT_BACK = 4,       /* the inport's topic has a publisher again */
    LN_WAIT_REQUESTS = 5,   /* the service group has requests: handle them with
                             * ln_wait_and_handle_service_group_requests(clnt, group, 0) */
    LN_WAIT_PARAMETERS = 6, /* the parameter block has overrides for its next update() */
    LN_WAIT_FD = 7,         /* the file descriptor is ready: `events` holds LN_WAIT_READABLE...*/
    LN_WAIT_TIMER = 8,      /* the timer expired `count` times since it was last reported */
    LN_WAIT_TRIGGER = 9     /* ln_waitset_trigger was called (`count` times) */
};

/* Inport conditions (ln_waitset_attach_inport flags). */
#define LN_WAIT_ON_DATA 0x1u       /* LN_WAIT_DATA */
#define LN_WAIT_ON_LIVELINESS 0x2u /* LN_WAIT_GONE / LN_WAIT_BACK */
/* File descriptor conditions and what fired (poll(2) meanings). */
#define LN_WAIT_READABLE 0x1u
#define LN_WAIT_WRITABLE 0x2u
#define LN_WAIT_ERROR 0x4u /* reported only: an error or hang-up on the descriptor */

#define LN_WAITSET_MAX_ATTACHMENTS 65535 /* attachments of one waitset at a time */
#define LN_WAITSET_TRIGGER_ID 0u         /* the id of LN_WAIT_TRIGGER events */

typedef struct ln_waitset_event {
    uint32_t id;     /* the attachment, as its attach call gave it (never 0) */
    uint32_t kind;   /* enum ln_waitset_kind */
    uint32_t events; /* LN_WAIT_FD: LN_WAIT_READABLE | _WRITABLE | _ERROR */
    uint32_t count;  /* LN_WAIT_TIMER / LN_WAIT_DEADLINE / LN_WAIT_TRIGGER: times it fired
                      * since last reported (timers that fell behind skip, never burst); else 1 */
    void* user_data; /* as given at attach (NULL for LN_WAIT_TRIGGER) */
} ln_waitset_event;

LN_EXPORT int ln_waitset_create(ln_waitset** out);
/* Detaches everything and frees the waitset; LN_EBUSY while another thread waits in it. */
LN_EXPORT int ln_waitset_destroy(ln_waitset* ws);

/* Each attach returns the attachment's id (> 0) in *id (may be NULL) and its user_data comes
 * back with every event of it.  Errors: LN_EBADHANDLE (a closed port, a destroyed handle),
 * LN_EBUSY (attached to a waitset already; a service group handled by a thread pool),
 * LN_ENOTFOUND (a group with no registered provider), LN_ELIMIT, LN_EINVAL.
 *
 * An inport: `flags` LN_WAIT_ON_* (0 means LN_WAIT_ON_DATA); `deadline` > 0 reports
 * LN_WAIT_DEADLINE each time that many seconds pass without a new sample (counted from the
 * attach, the last sample, or the last deadline report), 0 none. */
LN_EXPORT int ln_waitset_attach_inport(ln_waitset* ws, ln_inport* port, uint32_t flags,
                                       double deadline, void* user_data, uint32_t* id);
/* Change an inport attachment's deadline (seconds, 0: none), counted from now. */
LN_EXPORT int ln_waitset_set_deadline(ln_waitset* ws, uint32_t id, double deadline);
/* The requests of a service group of clnt (NULL or "": the default group), or of the group a
 * provider or event handler is registered in (register it first). */
LN_EXPORT int ln_waitset_attach_service_group(ln_waitset* ws, ln_client* clnt, const char* group,
                                              void* user_data, uint32_t* id);
LN_EXPORT int ln_waitset_attach_provider(ln_waitset* ws, ln_service_provider* provider,
                                         void* user_data, uint32_t* id);
LN_EXPORT int ln_waitset_attach_event_handler(ln_waitset* ws, ln_event_handler* handler,
                                              void* user_data, uint32_t* id);
/* Overrides that arrived for the block (registered or not yet): take them with update(). */
LN_EXPORT int ln_waitset_attach_parameter_block(ln_waitset* ws, ln_parameter_block* blk,
                                                void* user_data, uint32_t* id);
/* A file descriptor the caller owns and keeps open while attached; events LN_WAIT_READABLE
 * and/or LN_WAIT_WRITABLE, reported while they hold (level-triggered). */
LN_EXPORT int ln_waitset_attach_fd(ln_waitset* ws, int fd, uint32_t events, void* user_data,
                                   uint32_t* id);
/* An interval timer: first expiry at `first_ns` (CLOCK_MONOTONIC, ns; 0: now + period), then
 * every `period` seconds after the previous expiry time (> 0; 0: once only), on absolute
 * times, so it does not drift. */
LN_EXPORT int ln_waitset_attach_timer(ln_waitset* ws, int64_t first_ns, double period,
                                      void* user_data, uint32_t* id);
/* Ends an attachment; its pending events are dropped.  LN_ENOTFOUND for an unknown id. */
LN_EXPORT int ln_waitset_detach(ln_waitset* ws, uint32_t id);

/* Wait up to `timeout` seconds (< 0: forever, 0: only what is ready now) until something
 * fires, and fill ready[0..n) with what did.  Returns how many events it wrote (0: the
 * timeout passed), LN_EINTR if a signal handler ran meanwhile (nothing lost: wait again),
 * LN_EINVAL (ready NULL or n 0, NaN timeout), LN_EBUSY (another thread waits already). */
LN_EXPORT int ln_waitset_wait(ln_waitset* ws, double timeout, ln_waitset_event* ready, size_t n);
/* Wake a wait from any thread (or a signal handler): it reports LN_WAIT_TRIGGER. */
LN_EXPORT int ln_waitset_trigger(ln_waitset* ws);

/* For event loops (asyncio, GLib, ...): a descriptor that becomes readable when a wait may
 * have something to report, and the next time a timer or deadline falls due (CLOCK_MONOTONIC
 * ns, or -1 for none; now when events are pending, e.g. an inport reported last time still
 * has unread samples): add the descriptor to the loop, call ln_waitset_wait(ws, 0, ...) when
 * it is readable or that time has come.  The descriptor belongs to the waitset. */
LN_EXPORT int ln_waitset_fd(const ln_waitset* ws);
LN_EXPORT int ln_waitset_next_due(ln_waitset* ws, int64_t* monotonic_ns);

#ifdef __cplusplus
}
#endif

#endif /* LN_LN_H */
