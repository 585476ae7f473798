/* event_handler.c — the handler side of events: connecting a handler (a service provider named
 * ln_event/EVENT/CLIENT.N, plus its connect struct kept by the manager; both registered again
 * after a reconnect), running it for each call and answering with its reply. */
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "event_internal.h"
#include "json_scan.h"
#include "waitset_internal.h"

#define LN_EVENT_HANDLER_MAGIC 0x4c4e4548u
#define LN_EVENT_REQUEST_MAGIC 0x4c4e4552u
#define CLIENT_PART_MAX 64 /* bytes of the client name in a handler's service name */
#define NAME_ATTEMPTS 8    /* service names tried when one is taken */

struct ln_event_handler {
    uint32_t magic;
    ln_client* clnt;
    char event[LN_EVENT_MAX_NAME + 1];
    char name[LN_SVC_MAX_NAME + 1];
    ln_sig* connect_sig;
    ln_sig* call_sig;
    char* command; /* the event_connect command, sent again after a reconnect */
    ln_service_provider* prov;
    ln_event_handler_fn fn;
    void* user_data;
};

struct ln_event_request {
    uint32_t magic;
    ln_event_handler* h;
    ln_service_request* req;
    int answered;
};

static atomic_uint handler_counter;

static void handler_free(ln_event_handler* h)
{
    ln_sig_free(h->connect_sig);
    ln_sig_free(h->call_sig);
    free(h->command);
    h->magic = 0;
    free(h);
}

static int handler_check(const ln_event_handler* h)
{
    if (h == NULL || h->magic != LN_EVENT_HANDLER_MAGIC)
        return ln_set_error(NULL, LN_EBADHANDLE, "invalid event handler handle");
    return LN_OK;
}

static int request_check(const ln_event_request* call)
{
    if (call == NULL || call->magic != LN_EVENT_REQUEST_MAGIC)
        return ln_set_error(NULL, LN_EBADHANDLE,
                            "invalid event call (use it only inside its "
                            "handler)");
    return LN_OK;
}

/* ---- a call ---- */

static int respond(ln_event_request* call, int has_reply, uint32_t len, const void* data)
{
    uint8_t resp[LN_EVENT_REPLY_SIZE];
    ln_event_reply_pack(resp, has_reply, len, data);
    int rc = ln_service_request_respond(call->req, resp);
    call->answered = 1;
    return rc;
}

static int on_call(ln_client* clnt, ln_service_request* req, void* user_data)
{
    ln_event_handler* h = user_data;
    ln_event_request call = {LN_EVENT_REQUEST_MAGIC, h, req, 0};
    int rc = h->fn(clnt, &call, h->user_data);
    call.magic = 0;
    if (call.answered)
        return 0;
    if (rc < 0)
        return rc; /* the provider answers the error */
    return respond(&call, 0, 0, NULL);
}

int ln_event_request_get_data(ln_event_request* call, void* data)
{
    int rc = request_check(call);
    if (rc != LN_OK)
        return rc;
    return ln_service_request_get_data(call->req, data);
}

int ln_event_request_reply(ln_event_request* call, const void* reply)
{
    int rc = request_check(call);
    if (rc != LN_OK)
        return rc;
    ln_event_handler* h = call->h;
    if (call->answered)
        return ln_set_error(h->clnt, LN_EBUSY, "event \"%s\": this call is answered already",
                            h->event);
    if (reply == NULL && ln_sig_size(h->call_sig) > 0)
        return ln_set_error(h->clnt, LN_EINVAL, "event \"%s\": the reply is NULL", h->event);
    ln_wbuf wire;
    ln_wbuf_init(&wire);
    rc = ln_sig_encode(h->call_sig, reply, &wire, LN_SERVICE_DEFAULT_MAX_SIZE);
    if (rc != LN_OK) {
        ln_wbuf_free(&wire);
        return ln_set_error(h->clnt, rc, "event \"%s\": cannot encode the reply: %s", h->event,
                            ln_last_error());
    }
    rc = respond(call, 1, (uint32_t)wire.len, wire.data);
    ln_wbuf_free(&wire);
    return rc;
}

int ln_event_request_reply_error(ln_event_request* call, const char* text)
{
    int rc = request_check(call);
    if (rc != LN_OK)
        return rc;
    if (call->answered)
        return ln_set_error(call->h->clnt, LN_EBUSY, "event \"%s\": this call is answered already",
                            call->h->event);
    rc = ln_service_request_respond_error(call->req, text);
    call->answered = 1;
    return rc;
}

const char* ln_event_request_event_name(const ln_event_request* call)
{
    return request_check(call) == LN_OK ? call->h->event : NULL;
}

/* ---- connecting ---- */

/* After a reconnect (ports and request locks held; the provider, an older port, is registered
 * again already): give the manager the connect struct again. */
static int reclaim_handler(ln_client* clnt, void* handler)
{
    ln_event_handler* h = handler;
    ln_wbuf body;
    ln_wbuf_init(&body);
    ln_msg_control request = {.command = ln_strv_of(h->command)};
    ln_msg_control_write_after_id(&body, &request);
    uint16_t type;
    ln_rbuf reply;
    int rc = ln_client_request_locked(clnt, LN_MSG_CONTROL, &body, &type, &reply);
    ln_wbuf_free(&body);
    char answer[512] = "";
    if (rc == LN_OK) {
        ln_msg_control_result result = {0};
        ln_msg_control_result_read_after_id(&reply, &result); /* checked by the request */
        snprintf(answer, sizeof answer, "%.*s", (int)result.result.len, result.result.s);
        /* An answer cut short reads as refused, with the start of it in the text. */
        if (ln_json_bool(answer, "ok") != 1)
            rc = LN_EREFUSED;
    }
    if (rc != LN_OK)
        return ln_set_error(clnt, rc,
                            "event \"%s\": the manager refused to take back handler "
                            "\"%s\": %s",
                            h->event, h->name, answer[0] ? answer : ln_last_error());
    return LN_OK;
}

static void handler_close_fn(void* handler) { ln_event_disconnect(handler); }

static const ln_client_port_ops handler_ops = {handler_close_fn, reclaim_handler};

/* "ln_event/EVENT/CLIENT.N" with the client name reduced to service name characters. */
static void make_name(ln_event_handler* h)
{
    char part[CLIENT_PART_MAX + 1];
    const char* cn = ln_client_name(h->clnt);
    size_t n = 0;
    for (; cn[n] != '\0' && n < CLIENT_PART_MAX; n++) {
        char c = cn[n];
        int ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                 c == '_' || c == '-' || c == '.';
        part[n] = ok ? c : '_';
    }
    part[n] = '\0';
    snprintf(h->name, sizeof h->name, LN_EVENT_SERVICE_PREFIX "%s/%s.%u", h->event, part,
             atomic_fetch_add(&handler_counter, 1) + 1);
}

/* The event_connect command for the manager (malloc'd), or NULL. */
static char* connect_command(const ln_event_handler* h, const char* md_name, uint64_t layout_hash,
                             const char* signature, const char* hex)
{
    char* text = NULL;
    size_t size = 0;
    FILE* f = open_memstream(&text, &size);
    if (f == NULL)
        return NULL;
    fputs("{\"op\": \"event_connect\", \"event\": ", f);
    ln_event_json_quote(f, h->event);
    fputs(", \"service\": ", f);
    ln_event_json_quote(f, h->name);
    fputs(", \"md_name\": ", f);
    ln_event_json_quote(f, md_name);
    fprintf(f,
            ", \"layout_hash\": \"0x%016llx\", \"signature\": ", (unsigned long long)layout_hash);
    ln_event_json_quote(f, signature);
    fprintf(f, ", \"connect\": \"%s\"}", hex);
    if (fclose(f) != 0) {
        free(text);
        return NULL;
    }
    return text;
}

/* Registers the handler's service under a free name. */
static int provide(ln_event_handler* h, const char* md_name, uint64_t layout_hash,
                   const char* handler_sig, const char* group)
{
    int rc = LN_OK;
    for (int attempt = 0; attempt < NAME_ATTEMPTS; attempt++) {
        make_name(h);
        rc = ln_get_service_provider(h->clnt, &h->prov, h->name, md_name, layout_hash, handler_sig);
        if (rc != LN_OK)
            return rc;
        rc = ln_service_provider_set_handler(h->prov, on_call, h);
        if (rc == LN_OK)
            rc = ln_service_provider_register(h->prov, group);
        if (rc == LN_OK)
            return LN_OK;
        char text[LN_ERROR_TEXT_MAX];
        snprintf(text, sizeof text, "%s", ln_last_error());
        ln_unregister_service_provider(h->prov);
        h->prov = NULL;
        ln_set_error(h->clnt, rc, "%s", text);
        if (rc != LN_EEXIST)
            return rc;
    }
    return rc;
}

int ln_event_connect(ln_client* clnt, ln_event_handler** out, const char* event,
                     const char* md_name, uint64_t layout_hash, const char* signature,
                     const void* connect, ln_event_handler_fn handler, void* user_data,
                     const char* group)
{
    int rc = ln_client_check(clnt);
    if (rc != LN_OK)
        return rc;
    if (out == NULL)
        return ln_set_error(clnt, LN_EINVAL, "ln_event_connect: out must not be NULL");
    *out = NULL;
    if ((rc = ln_event_check_name(clnt, "ln_event_connect", event)) != LN_OK)
        return rc;
    if (md_name == NULL || signature == NULL || handler == NULL)
        return ln_set_error(clnt, LN_EINVAL,
                            "ln_event_connect: event \"%s\": md name, "
                            "signature and handler are required",
                            event);
    ln_event_handler* h = calloc(1, sizeof *h);
    if (h == NULL)
        return ln_set_error(clnt, LN_ENOMEM, "out of memory for a handler of event \"%s\"", event);
    h->clnt = clnt;
    h->fn = handler;
    h->user_data = user_data;
    snprintf(h->event, sizeof h->event, "%s", event);
    char* handler_sig = NULL;
    rc = ln_event_parse_signature(clnt, md_name, signature, &h->connect_sig, &h->call_sig,
                                  &handler_sig);
    ln_wbuf wire;
    ln_wbuf_init(&wire);
    if (rc == LN_OK && connect == NULL && ln_sig_size(h->connect_sig) > 0)
        rc = ln_set_error(clnt, LN_EINVAL, "event \"%s\": the connect struct is NULL", event);
    if (rc == LN_OK &&
        (rc = ln_sig_encode(h->connect_sig, connect, &wire, LN_EVENT_MAX_CONNECT_SIZE)) != LN_OK)
        rc = ln_set_error(clnt, rc,
                          "event \"%s\": connect struct: %s (at most %d bytes in "
                          "wire form)",
                          event, ln_last_error(), LN_EVENT_MAX_CONNECT_SIZE);
    if (rc == LN_OK)
        rc = provide(h, md_name, layout_hash, handler_sig, group);
    if (rc == LN_OK) {
        char hex[2 * LN_EVENT_MAX_CONNECT_SIZE + 1];
        ln_event_hex(wire.data, wire.len, hex);
        h->command = connect_command(h, md_name, layout_hash, signature, hex);
        if (h->command == NULL)
            rc = ln_set_error(clnt, LN_ENOMEM, "event \"%s\": out of memory", event);
    }
    if (rc == LN_OK && (rc = ln_control(clnt, h->command, NULL)) != LN_OK)
        rc = ln_set_error(clnt, rc, "cannot connect a handler to event \"%s\": %s", event,
                          ln_last_error());
    if (rc == LN_OK) {
        /* From here on a reconnect gives the manager the connect struct again (at once if
         * one happened since the command went out). */
        uint64_t gen = ln_client_request_gen();
        h->magic = LN_EVENT_HANDLER_MAGIC;
        rc = ln_client_add_port(clnt, h, &handler_ops, gen);
    }
    free(handler_sig);
    ln_wbuf_free(&wire);
    if (rc != LN_OK) {
        if (h->prov != NULL) {
            char text[LN_ERROR_TEXT_MAX];
            snprintf(text, sizeof text, "%s", ln_last_error());
            ln_unregister_service_provider(h->prov);
            ln_set_error(clnt, rc, "%s", text);
        }
        handler_free(h);
        return rc;
    }
    *out = h;
    return LN_OK;
}

int ln_event_disconnect(ln_event_handler* h)
{
    int rc = handler_check(h);
    if (rc != LN_OK)
        return rc;
    /* Unregistering the service makes the manager forget the connect struct too. */
    rc = ln_unregister_service_provider(h->prov);
    if (rc != LN_OK)
        return rc == LN_EBUSY ? ln_set_error(h->clnt, rc,
                                             "event \"%s\": a handler cannot disconnect "
                                             "itself while it runs",
                                             h->event)
                              : rc;
    ln_client_remove_port(h->clnt, h);
    handler_free(h);
    return LN_OK;
}

const char* ln_event_handler_name(const ln_event_handler* h)
{
    return handler_check(h) == LN_OK ? h->name : NULL;
}

/* ---- waitsets (waitset_internal.h) ---- */

int ln_event_handler_provider(const ln_event_handler* h, ln_service_provider** prov)
{
    int rc = handler_check(h);
    if (rc == LN_OK)
        *prov = h->prov;
    return rc;
}
