/* event_call.c — the caller side of events: asking the manager which handlers are connected
 * (keeping a connection to each between calls), sending one call to all of them before waiting
 * for any answer, and the per-handler results with their replies. */
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "event_internal.h"
#include "json_scan.h"
#include "net.h"

#define LN_EVENT_MAGIC 0x4c4e4543u
#define ERROR_MAX 512
#define CLIENT_MAX 256

typedef struct handler_entry {
    char name[LN_SVC_MAX_NAME + 1];
    char client[CLIENT_MAX];
    ln_service* svc; /* NULL until the first call that goes to it */
    void* connect;   /* its connect struct (in `arena`) */
    ln_arena arena;
    /* of the last call */
    int selected, sent, code;
    void* reply;
    char error[ERROR_MAX];
    uint8_t resp[LN_EVENT_REPLY_SIZE];
} handler_entry;

struct ln_event {
    uint32_t magic;
    ln_client* clnt;
    char name[LN_EVENT_MAX_NAME + 1];
    char md_name[LN_SVC_MAX_NAME + 1];
    uint64_t layout_hash;
    char* handler_sig;
    ln_sig* connect_sig;
    ln_sig* call_sig;
    ln_event_filter filter;
    void* filter_data;

    pthread_mutex_t lock;    /* one call at a time; guards everything below */
    handler_entry** entries; /* as the manager listed them last, by name */
    size_t nentries;
    int listed;       /* a list came at least once */
    ln_arena replies; /* decoded replies of the last call */
};

static int event_check(const ln_event* ev)
{
    if (ev == NULL || ev->magic != LN_EVENT_MAGIC)
        return ln_set_error(NULL, LN_EBADHANDLE, "invalid event handle");
    return LN_OK;
}

static void entry_free(handler_entry* e)
{
    if (e->svc != NULL)
        ln_service_release(e->svc);
    ln_arena_free(&e->arena);
    free(e);
}

static void event_free(ln_event* ev)
{
    for (size_t i = 0; i < ev->nentries; i++)
        entry_free(ev->entries[i]);
    free(ev->entries);
    ln_arena_free(&ev->replies);
    ln_sig_free(ev->connect_sig);
    ln_sig_free(ev->call_sig);
    free(ev->handler_sig);
    pthread_mutex_destroy(&ev->lock);
    ev->magic = 0;
    free(ev);
}

static void event_close_fn(void* ev) { ln_event_release(ev); }

/* A caller registers nothing; it asks for the handlers on every call. */
static int event_reclaim(ln_client* clnt, void* ev)
{
    (void)clnt;
    (void)ev;
    return LN_OK;
}

static const ln_client_port_ops event_ops = {event_close_fn, event_reclaim};

int ln_get_event(ln_client* clnt, ln_event** out, const char* event, const char* md_name,
                 uint64_t layout_hash, const char* signature)
{
    int rc = ln_client_check(clnt);
    if (rc != LN_OK)
        return rc;
    if (out == NULL)
        return ln_set_error(clnt, LN_EINVAL, "ln_get_event: out must not be NULL");
    *out = NULL;
    if ((rc = ln_event_check_name(clnt, "ln_get_event", event)) != LN_OK)
        return rc;
    if (md_name == NULL || signature == NULL || md_name[0] == '\0' ||
        strlen(md_name) > LN_SVC_MAX_NAME)
        return ln_set_error(clnt, LN_EINVAL,
                            "ln_get_event: event \"%s\": md name (1..%d "
                            "bytes) and signature are required",
                            event, LN_SVC_MAX_NAME);
    ln_event* ev = calloc(1, sizeof *ev);
    if (ev == NULL)
        return ln_set_error(clnt, LN_ENOMEM, "out of memory for event \"%s\"", event);
    ev->clnt = clnt;
    snprintf(ev->name, sizeof ev->name, "%s", event);
    snprintf(ev->md_name, sizeof ev->md_name, "%s", md_name);
    ev->layout_hash = layout_hash;
    pthread_mutex_init(&ev->lock, NULL);
    ln_arena_init(&ev->replies, 0);
    rc = ln_event_parse_signature(clnt, md_name, signature, &ev->connect_sig, &ev->call_sig,
                                  &ev->handler_sig);
    if (rc == LN_OK) {
        ev->magic = LN_EVENT_MAGIC;
        rc = ln_client_add_port(clnt, ev, &event_ops, 0);
    }
    if (rc != LN_OK) {
        event_free(ev);
        return rc;
    }
    *out = ev;
    return LN_OK;
}

int ln_event_set_filter(ln_event* ev, ln_event_filter filter, void* user_data)
{
    int rc = event_check(ev);
    if (rc != LN_OK)
        return rc;
    pthread_mutex_lock(&ev->lock);
    ev->filter = filter;
    ev->filter_data = user_data;
    pthread_mutex_unlock(&ev->lock);
    return LN_OK;
}

int ln_event_release(ln_event* ev)
{
    int rc = event_check(ev);
    if (rc != LN_OK)
        return rc;
    ln_client_remove_port(ev->clnt, ev);
    pthread_mutex_lock(&ev->lock); /* a call in another thread ends first */
    pthread_mutex_unlock(&ev->lock);
    event_free(ev);
    return LN_OK;
}

/* ---- the handler list ---- */

static handler_entry* take_entry(ln_event* ev, const char* name)
{
    for (size_t i = 0; i < ev->nentries; i++) {
        handler_entry* e = ev->entries[i];
        if (e != NULL && strcmp(e->name, name) == 0) {
            ev->entries[i] = NULL;
            return e;
        }
    }
    handler_entry* e = calloc(1, sizeof *e);
    if (e != NULL) {
        snprintf(e->name, sizeof e->name, "%s", name);
        ln_arena_init(&e->arena, 0);
    }
    return e;
}

/* One element of "handlers" into an entry of `list`.  LN_OK, or an error (recorded). */
static int add_handler(ln_event* ev, const char* item, handler_entry** list, size_t* n)
{
    char name[LN_SVC_MAX_NAME + 1], client[CLIENT_MAX], hex[2 * LN_EVENT_MAX_CONNECT_SIZE + 1];
    uint8_t wire[LN_EVENT_MAX_CONNECT_SIZE];
    size_t len;
    if (ln_json_string(item, "service", name, sizeof name) != 0 ||
        ln_json_string(item, "client", client, sizeof client) != 0 ||
        ln_json_string(item, "connect", hex, sizeof hex) != 0 ||
        ln_event_unhex(hex, wire, sizeof wire, &len) != 0)
        return ln_set_error(ev->clnt, LN_EPROTOCOL,
                            "event \"%s\": the manager's handler list "
                            "is malformed",
                            ev->name);
    handler_entry* e = take_entry(ev, name);
    if (e == NULL)
        return ln_set_error(ev->clnt, LN_ENOMEM, "event \"%s\": out of memory", ev->name);
    list[(*n)++] = e;
    snprintf(e->client, sizeof e->client, "%s", client);
    ln_arena_reset(&e->arena);
    size_t size = ln_sig_size(ev->connect_sig);
    e->connect = ln_arena_alloc(&e->arena, size ? size : 1);
    if (e->connect == NULL)
        return ln_set_error(ev->clnt, LN_ENOMEM, "event \"%s\": out of memory", ev->name);
    int rc = ln_sig_decode(ev->connect_sig, wire, len, e->connect, &e->arena,
                           LN_EVENT_MAX_CONNECT_SIZE * 64);
    if (rc != LN_OK)
        return ln_set_error(ev->clnt, rc, "event \"%s\": connect struct of handler \"%s\": %s",
                            ev->name, name, ln_last_error());
    return LN_OK;
}

/* Reads the event's entry of an `events` answer into a new list of entries (reusing the
 * connections of entries already known) and makes it the handle's list. */
static int take_list(ln_event* ev, const char* answer)
{
    const char* pos = ln_json_array(answer, "events");
    const char* start;
    size_t len;
    if (pos == NULL)
        return ln_set_error(ev->clnt, LN_EPROTOCOL,
                            "event \"%s\": the manager's answer has "
                            "no event list",
                            ev->name);
    int found = ln_json_next(&pos, &start, &len);
    if (found < 0)
        return ln_set_error(ev->clnt, LN_EPROTOCOL,
                            "event \"%s\": the manager's event list "
                            "is malformed",
                            ev->name);
    handler_entry** list = calloc(LN_EVENT_MAX_HANDLERS, sizeof *list);
    char* item = found ? strndup(start, len) : NULL;
    size_t n = 0;
    int rc = list == NULL || (found && item == NULL)
                 ? ln_set_error(ev->clnt, LN_ENOMEM, "event \"%s\": out of memory", ev->name)
                 : LN_OK;
    if (rc == LN_OK && found) {
        char md_name[LN_SVC_MAX_NAME + 1], hash[32];
        if (ln_json_string(item, "md_name", md_name, sizeof md_name) != 0 ||
            ln_json_string(item, "layout_hash", hash, sizeof hash) != 0)
            rc = ln_set_error(ev->clnt, LN_EPROTOCOL,
                              "event \"%s\": the manager's event entry "
                              "is malformed",
                              ev->name);
        else if (strtoull(hash, NULL, 16) != ev->layout_hash)
            rc = ln_set_error(ev->clnt, LN_ELAYOUT,
                              "event \"%s\": layout of md \"%s\" (hash "
                              "0x%016llx) differs from its handlers' md \"%s\" (hash %s)",
                              ev->name, ev->md_name, (unsigned long long)ev->layout_hash, md_name,
                              hash);
        const char* hpos = rc == LN_OK ? ln_json_array(item, "handlers") : NULL;
        const char* hstart;
        size_t hlen;
        int more = 0;
        while (rc == LN_OK && hpos != NULL && (more = ln_json_next(&hpos, &hstart, &hlen)) == 1 &&
               n < LN_EVENT_MAX_HANDLERS) {
            char* h = strndup(hstart, hlen);
            rc = h == NULL ? ln_set_error(ev->clnt, LN_ENOMEM, "out of memory")
                           : add_handler(ev, h, list, &n);
            free(h);
        }
        if (rc == LN_OK && (hpos == NULL || more < 0))
            rc = ln_set_error(ev->clnt, LN_EPROTOCOL,
                              "event \"%s\": the manager's handler "
                              "list is malformed",
                              ev->name);
    }
    free(item);
    if (rc != LN_OK) { /* the entries taken go back */
        for (size_t i = 0; i < n; i++)
            entry_free(list[i]);
        free(list);
        return rc;
    }
    for (size_t i = 0; i < ev->nentries; i++) /* handlers that are gone */
        if (ev->entries[i] != NULL)
            entry_free(ev->entries[i]);
    free(ev->entries);
    ev->entries = list;
    ev->nentries = n;
    ev->listed = 1;
    return LN_OK;
}

/* Asks the manager for the handlers.  Without an answer (manager away) the last list stays,
 * if there is one. */
static int refresh(ln_event* ev)
{
    char* command = NULL;
    size_t size = 0;
    FILE* f = open_memstream(&command, &size);
    if (f == NULL)
        return ln_set_error(ev->clnt, LN_ENOMEM, "event \"%s\": out of memory", ev->name);
    fputs("{\"op\": \"events\", \"name\": ", f);
    ln_event_json_quote(f, ev->name);
    fputc('}', f);
    if (fclose(f) != 0) {
        free(command);
        return ln_set_error(ev->clnt, LN_ENOMEM, "event \"%s\": out of memory", ev->name);
    }
    char* answer = NULL;
    int rc = ln_control(ev->clnt, command, &answer);
    free(command);
    if (rc == LN_ECONNECTION && ev->listed)
        return LN_OK;
    if (rc != LN_OK)
        return ln_set_error(ev->clnt, rc,
                            "event \"%s\": cannot ask the manager for its "
                            "handlers: %s",
                            ev->name, ln_last_error());
    rc = take_list(ev, answer);
    ln_free(answer);
    return rc;
}

/* ---- a call ---- */

static void entry_failed(handler_entry* e, int code)
{
    e->code = code;
    snprintf(e->error, sizeof e->error, "%s", ln_last_error());
}

/* Sends the call to every selected handler (connecting to new ones first). */
static void send_all(ln_event* ev, const void* call, const struct timespec* deadline)
{
    for (size_t i = 0; i < ev->nentries; i++) {
        handler_entry* e = ev->entries[i];
        if (!e->selected)
            continue;
        int rc = LN_OK;
        if (e->svc == NULL) {
            rc = ln_get_service(ev->clnt, &e->svc, e->name, ev->md_name, ev->layout_hash,
                                ev->handler_sig);
            if (rc == LN_OK) /* the event releases it, not the client */
                ln_client_remove_port(ev->clnt, e->svc);
            else
                e->svc = NULL;
        }
        if (rc == LN_OK)
            rc = ln_svc_call_send(e->svc, call, deadline);
        if (rc == LN_OK)
            e->sent = 1;
        else
            entry_failed(e, rc);
    }
}

/* Waits for the answer of every handler the call went to. */
static int receive_all(ln_event* ev, const struct timespec* deadline)
{
    int delivered = 0;
    size_t size = ln_sig_size(ev->call_sig);
    for (size_t i = 0; i < ev->nentries; i++) {
        handler_entry* e = ev->entries[i];
        if (!e->sent)
            continue;
        int rc = ln_svc_call_receive(e->svc, e->resp, deadline);
        int has_reply = 0;
        uint32_t len = 0;
        const uint8_t* data = NULL;
        if (rc == LN_OK)
            ln_event_reply_unpack(e->resp, &has_reply, &len, &data);
        if (rc == LN_OK && has_reply) {
            e->reply = ln_arena_alloc(&ev->replies, size ? size : 1);
            rc = e->reply == NULL
                     ? ln_set_error(ev->clnt, LN_ENOMEM, "event \"%s\": out of memory", ev->name)
                     : ln_sig_decode(ev->call_sig, data, len, e->reply, &ev->replies,
                                     LN_SERVICE_DEFAULT_MAX_SIZE);
            if (rc != LN_OK) {
                rc = ln_set_error(ev->clnt, rc,
                                  "event \"%s\": bad reply from handler \"%s\": "
                                  "%s",
                                  ev->name, e->name, ln_last_error());
                e->reply = NULL;
            }
        }
        if (rc == LN_OK)
            delivered++;
        else
            entry_failed(e, rc);
    }
    return delivered;
}

static void clear_results(ln_event* ev)
{
    ln_arena_reset(&ev->replies);
    for (size_t i = 0; i < ev->nentries; i++) {
        handler_entry* e = ev->entries[i];
        e->selected = e->sent = 0;
        e->code = LN_OK;
        e->error[0] = '\0';
        e->reply = NULL;
    }
}

static int call_locked(ln_event* ev, const void* call, double timeout)
{
    clear_results(ev);
    int rc = refresh(ev);
    if (rc != LN_OK)
        return rc;
    clear_results(ev);
    for (size_t i = 0; i < ev->nentries; i++) { /* the filter sees every handler first */
        handler_entry* e = ev->entries[i];
        int want = ev->filter != NULL ? ev->filter(e->connect, ev->filter_data) : 1;
        if (want < 0) {
            for (size_t j = 0; j < ev->nentries; j++)
                ev->entries[j]->selected = 0;
            return ln_set_error(ev->clnt, want,
                                "event \"%s\": the filter stopped the call at "
                                "handler \"%s\" (%s)",
                                ev->name, e->name, ln_error_name(want) ? ln_error_name(want) : "?");
        }
        e->selected = want > 0;
    }
    struct timespec ts;
    const struct timespec* deadline = isinf(timeout) ? NULL : ln_net_deadline(&ts, timeout);
    send_all(ev, call, deadline);
    return receive_all(ev, deadline);
}

int ln_event_call(ln_event* ev, const void* call, double timeout)
{
    int rc = event_check(ev);
    if (rc != LN_OK)
        return rc;
    if (isnan(timeout))
        return ln_set_error(ev->clnt, LN_EINVAL, "event \"%s\": timeout is NaN", ev->name);
    if (call == NULL && ln_sig_size(ev->call_sig) > 0)
        return ln_set_error(ev->clnt, LN_EINVAL, "event \"%s\": the call struct is NULL", ev->name);
    pthread_mutex_lock(&ev->lock);
    rc = call_locked(ev, call, timeout);
    pthread_mutex_unlock(&ev->lock);
    return rc;
}

/* ---- results ---- */

int ln_event_result_count(const ln_event* ev)
{
    int rc = event_check(ev);
    if (rc != LN_OK)
        return rc;
    ln_event* e = (ln_event*)ev; /* the lock is not part of the logical state */
    pthread_mutex_lock(&e->lock);
    int n = 0;
    for (size_t i = 0; i < e->nentries; i++)
        n += e->entries[i]->selected;
    pthread_mutex_unlock(&e->lock);
    return n;
}

int ln_event_get_result(const ln_event* ev, size_t index, ln_event_result* out)
{
    int rc = event_check(ev);
    if (rc != LN_OK)
        return rc;
    if (out == NULL)
        return ln_set_error(ev->clnt, LN_EINVAL, "ln_event_get_result: out is NULL");
    ln_event* e = (ln_event*)ev;
    pthread_mutex_lock(&e->lock);
    rc = LN_EINVAL;
    size_t k = 0;
    for (size_t i = 0; i < e->nentries; i++) {
        const handler_entry* h = e->entries[i];
        if (!h->selected || k++ != index)
            continue;
        *out = (ln_event_result){h->name, h->client, h->code, h->error, h->connect, h->reply};
        rc = LN_OK;
        break;
    }
    pthread_mutex_unlock(&e->lock);
    if (rc != LN_OK)
        return ln_set_error(ev->clnt, rc, "event \"%s\": the last call has no result %zu", ev->name,
                            index);
    return LN_OK;
}
