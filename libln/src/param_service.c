/* param_service.c — the service of a parameter block (md ln/parameters/query, docs/parameters.md
 * "Wire"): list, get (with the loop's live values), set (one parameter, or several at once,
 * all or nothing) and reset, answered on libln's service thread; and the initial overrides a
 * process gets from the manager in $LN_PARAMETERS. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "client_internal.h"
#include "param_internal.h"
#include "param_messages.h"

#define DEFAULT_WAIT 0.25 /* s a get waits for the loop's next update() */
#define MAX_WAIT 10.0

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* ---- answers ---- */

static void write_param(ln_pbuf* o, const ln_parameter_block* b, uint32_t i, uint64_t applied)
{
    const ln_param* p = &b->params[i];
    ln_pbuf_add(o, "{\"name\": ");
    ln_pbuf_quote(o, p->name, strlen(p->name));
    ln_pbuf_add(o, ", \"type\": \"%s\", \"count\": %u, \"description\": ", p->type->name, p->count);
    ln_pbuf_quote(o, p->description, strlen(p->description));
    ln_pbuf_add(
        o, ", \"read_only\": %s, \"min\": ", p->flags & LN_PARAMETER_READ_ONLY ? "true" : "false");
    if (p->flags & LN_PARAMETER_MIN)
        ln_pbuf_double(o, p->min, 0);
    else
        ln_pbuf_add(o, "null");
    ln_pbuf_add(o, ", \"max\": ");
    if (p->flags & LN_PARAMETER_MAX)
        ln_pbuf_double(o, p->max, 0);
    else
        ln_pbuf_add(o, "null");
    ln_pbuf_add(o, ", \"has_input\": %s, \"value\": ", p->has_input ? "true" : "false");
    ln_param_write(o, p, b->known_out + p->offset);
    ln_pbuf_add(o, ", \"input\": ");
    ln_param_write(o, p, b->known_in + p->offset);
    ln_pbuf_add(o, ", \"overridden\": %s", p->overridden ? "true" : "false");
    if (p->overridden) {
        ln_pbuf_add(o, ", \"override\": ");
        ln_param_write(o, p, b->values + p->offset);
        ln_pbuf_add(o, ", \"source\": \"%s\"", p->source);
    }
    ln_pbuf_add(o, ", \"generation\": %llu, \"pending\": %s}", (unsigned long long)p->gen,
                p->gen > applied ? "true" : "false");
}

static void write_block(ln_pbuf* o, const ln_parameter_block* b, int only, int live)
{
    uint64_t applied = atomic_load_explicit(&b->applied_gen, memory_order_acquire);
    ln_pbuf_add(o, "{\"block\": ");
    ln_pbuf_quote(o, b->name, strlen(b->name));
    const char* client = b->clnt != NULL ? ln_client_name(b->clnt) : "";
    ln_pbuf_add(o, ", \"client\": ");
    ln_pbuf_quote(o, client ? client : "", client ? strlen(client) : 0);
    ln_pbuf_add(o, ", \"service\": ");
    ln_pbuf_quote(o, b->service, strlen(b->service));
    ln_pbuf_add(o,
                ", \"generation\": %llu, \"applied_generation\": %llu, \"updates\": %llu, "
                "\"live\": %s, \"values_update\": %llu, \"config_errors\": %s, "
                "\"parameters\": [",
                (unsigned long long)b->generation, (unsigned long long)applied,
                (unsigned long long)atomic_load_explicit(&b->updates, memory_order_relaxed),
                live ? "true" : "false", (unsigned long long)b->known_update,
                b->config_errors ? b->config_errors : "[]");
    for (uint32_t i = 0; i < b->n; i++) {
        if (only >= 0 && (uint32_t)only != i)
            continue;
        if (only < 0 && i > 0)
            ln_pbuf_add(o, ", ");
        write_param(o, b, i, applied);
    }
    ln_pbuf_add(o, "]}");
}

/* Asks the loop for its inputs and outputs and waits up to `wait` s for its next update():
 * 1 if the known values are fresh now, 0 if the loop did not update in time. */
static int refresh(ln_parameter_block* b, double wait)
{
    atomic_store_explicit(&b->report_state, LN_REPORT_REQUESTED, memory_order_release);
    double deadline = now_s() + wait;
    for (;;) {
        uint32_t state = atomic_load_explicit(&b->report_state, memory_order_acquire);
        if (state == LN_REPORT_DONE) {
            memcpy(b->known_in, b->report_in, b->values_size);
            memcpy(b->known_out, b->report_out, b->values_size);
            b->known_update = b->report_update;
            atomic_store_explicit(&b->report_state, LN_REPORT_IDLE, memory_order_relaxed);
            return 1;
        }
        if (state == LN_REPORT_REQUESTED && now_s() >= deadline) {
            uint32_t expected = LN_REPORT_REQUESTED;
            if (atomic_compare_exchange_strong(&b->report_state, &expected, LN_REPORT_IDLE))
                return 0;
            continue; /* the loop is copying right now: take it */
        }
        struct timespec pause = {0, 50000};
        nanosleep(&pause, NULL);
    }
}

/* ---- changes ---- */

/* Takes the checked values in `staged` (a full copy of the value area) for the parameters
 * marked in `which`, as one change. */
static void commit(ln_parameter_block* b, const uint8_t* staged, const uint8_t* which,
                   const char* source)
{
    b->generation++;
    for (uint32_t i = 0; i < b->n; i++) {
        if (!which[i])
            continue;
        ln_param* p = &b->params[i];
        memcpy(b->values + p->offset, staged + p->offset, p->size);
        p->overridden = 1;
        p->gen = b->generation;
        p->source = source;
    }
    ln_param_history_add(b, source, which, staged);
    ln_param_publish(b);
}

/* The value (a JSON text) of one parameter, or with name "" a JSON object of several. */
static int do_set(ln_parameter_block* b, const char* name, const char* value, ln_pbuf* out,
                  ln_param_err* err)
{
    uint8_t* staged = malloc(b->values_size ? b->values_size : 1);
    uint8_t* which = calloc(b->n ? b->n : 1, 1);
    int rc = -1;
    if (staged == NULL || which == NULL) {
        ln_param_fail(err, "bad_request", "out of memory");
        goto out;
    }
    const char* cursor = value;
    if (name[0] != '\0') {
        int i = ln_param_find(b, name);
        if (i < 0) {
            ln_param_fail(err, "not_found", "block \"%s\" has no parameter \"%s\"", b->name, name);
            goto out;
        }
        if (ln_param_check(b, (uint32_t)i, &cursor, staged + b->params[i].offset, err) != 0)
            goto out;
        which[i] = 1;
    } else {
        int first = 1, more;
        char key[LN_PARAMETER_MAX_NAME + 2];
        if (ln_pj_open(&cursor, '{') != 0) {
            ln_param_fail(err, "bad_request",
                          "set without a name needs a JSON object "
                          "{\"parameter\": value, ...}");
            goto out;
        }
        while ((more = ln_pj_next_member(&cursor, &first, key, sizeof key)) == 1) {
            int i = ln_param_find(b, key);
            if (i < 0) {
                ln_param_fail(err, "not_found", "block \"%s\" has no parameter \"%s\"", b->name,
                              key);
                goto out;
            }
            if (which[i]) {
                ln_param_fail(err, "bad_request", "parameter \"%s\" is given twice", key);
                goto out;
            }
            if (ln_param_check(b, (uint32_t)i, &cursor, staged + b->params[i].offset, err) != 0)
                goto out;
            which[i] = 1;
        }
        if (more != 0) {
            ln_param_fail(err, "bad_request", "malformed JSON object near offset %zu",
                          (size_t)(cursor - value));
            goto out;
        }
    }
    if (*ln_pj_ws(cursor) != '\0') {
        ln_param_fail(err, "bad_request", "text after the value at offset %zu",
                      (size_t)(ln_pj_ws(cursor) - value));
        goto out;
    }
    commit(b, staged, which, "set");
    ln_pbuf_add(out, "{\"generation\": %llu, \"set\": [", (unsigned long long)b->generation);
    for (uint32_t i = 0, k = 0; i < b->n; i++)
        if (which[i]) {
            ln_pbuf_add(out, "%s", k++ ? ", " : "");
            ln_pbuf_quote(out, b->params[i].name, strlen(b->params[i].name));
        }
    ln_pbuf_add(out, "]}");
    rc = 0;
out:
    free(staged);
    free(which);
    return rc;
}

/* Marks in chosen[] the parameters a reset names: `name`, else the JSON array of names in
 * `value`, else every one.  0 or -1. */
static int reset_names(ln_parameter_block* b, const char* name, const char* value, uint8_t* chosen,
                       ln_param_err* err)
{
    if (name[0] != '\0') {
        int i = ln_param_find(b, name);
        if (i < 0)
            return ln_param_fail(err, "not_found", "block \"%s\" has no parameter \"%s\"", b->name,
                                 name);
        chosen[i] = 1;
        return 0;
    }
    const char* cursor = value;
    if (*ln_pj_ws(cursor) == '\0') {
        memset(chosen, 1, b->n);
        return 0;
    }
    int first = 1, more;
    char key[LN_PARAMETER_MAX_NAME + 2];
    if (ln_pj_open(&cursor, '[') != 0)
        return ln_param_fail(err, "bad_request",
                             "reset takes no value or a JSON list of "
                             "parameter names");
    while ((more = ln_pj_next_element(&cursor, &first)) == 1) {
        if (ln_pj_string(&cursor, key, sizeof key, NULL) != 0)
            return ln_param_fail(err, "bad_request", "reset: a list of names (strings)");
        int i = ln_param_find(b, key);
        if (i < 0)
            return ln_param_fail(err, "not_found", "block \"%s\" has no parameter \"%s\"", b->name,
                                 key);
        chosen[i] = 1;
    }
    if (more != 0 || *ln_pj_ws(cursor) != '\0')
        return ln_param_fail(err, "bad_request", "reset: malformed list of names");
    return 0;
}

static int do_reset(ln_parameter_block* b, const char* name, const char* value, ln_pbuf* out,
                    ln_param_err* err)
{
    uint8_t* which = calloc(b->n ? b->n : 1, 1);
    if (which == NULL)
        return ln_param_fail(err, "bad_request", "out of memory");
    if (reset_names(b, name, value, which, err) != 0) {
        free(which);
        return -1;
    }
    int any = 0;
    for (uint32_t i = 0; i < b->n; i++)
        any |= which[i] = which[i] && b->params[i].overridden;
    if (any)
        b->generation++;
    ln_pbuf_add(out, "{\"generation\": %llu, \"reset\": [", (unsigned long long)b->generation);
    for (uint32_t i = 0, k = 0; i < b->n; i++) {
        ln_param* p = &b->params[i];
        if (!which[i])
            continue;
        p->overridden = 0;
        p->gen = b->generation;
        ln_pbuf_add(out, "%s", k++ ? ", " : "");
        ln_pbuf_quote(out, p->name, strlen(p->name));
    }
    ln_pbuf_add(out, "]}");
    if (any) {
        ln_param_history_add(b, "reset", which, NULL);
        ln_param_publish(b);
    }
    free(which);
    return 0;
}

/* The value of get ({"wait": SECONDS}) or changes ({"since": GENERATION}): "" keeps
 * *number as it is. */
static int option(const char* op, const char* value, const char* key_wanted, double* number,
                  double max, ln_param_err* err)
{
    const char* cursor = value;
    if (*ln_pj_ws(cursor) == '\0')
        return 0;
    int first = 1, more;
    char key[16];
    if (ln_pj_open(&cursor, '{') != 0)
        goto bad;
    while ((more = ln_pj_next_member(&cursor, &first, key, sizeof key)) == 1) {
        const char* start;
        size_t len;
        if (strcmp(key, key_wanted) != 0 || ln_pj_number(&cursor, &start, &len) != 0)
            goto bad;
        *number = strtod(start, NULL);
        if (!(*number >= 0 && *number <= max))
            return ln_param_fail(err, "bad_request", "%s must be 0..%g", key_wanted, max);
    }
    if (more != 0 || *ln_pj_ws(cursor) != '\0')
        goto bad;
    return 0;
bad:
    return ln_param_fail(err, "bad_request", "%s takes no value or {\"%s\": NUMBER}", op,
                         key_wanted);
}

static int dispatch(ln_parameter_block* b, const char* op, const char* name, const char* value,
                    ln_pbuf* out, ln_param_err* err)
{
    if (strcmp(op, "list") == 0 || strcmp(op, "get") == 0) {
        int only = -1, live = 0;
        double wait = 0;
        if (name[0] != '\0' && (only = ln_param_find(b, name)) < 0)
            return ln_param_fail(err, "not_found", "block \"%s\" has no parameter \"%s\"", b->name,
                                 name);
        if (op[0] == 'g') {
            wait = DEFAULT_WAIT;
            if (option("get", value, "wait", &wait, MAX_WAIT, err) != 0)
                return -1;
            live = refresh(b, wait);
        }
        write_block(out, b, only, live);
        return 0;
    }
    if (strcmp(op, "set") == 0)
        return do_set(b, name, value, out, err);
    if (strcmp(op, "reset") == 0)
        return do_reset(b, name, value, out, err);
    if (strcmp(op, "changes") == 0) {
        double since = 0;
        if (option("changes", value, "since", &since, 9007199254740992.0, err) != 0)
            return -1;
        ln_param_history_write(b, (uint64_t)since, out);
        return 0;
    }
    return ln_param_fail(err, "bad_request",
                         "unknown op \"%.40s\" (list, get, set, reset, changes)", op);
}

int ln_param_request(ln_parameter_block* b, const char* op, const char* name, const char* value,
                     ln_pbuf* out, ln_param_err* err)
{
    pthread_mutex_lock(&b->lock);
    int rc = dispatch(b, op, name, value, out, err);
    pthread_mutex_unlock(&b->lock);
    return rc;
}

static char* text_of(const char* data, uint32_t len)
{
    char* s = malloc((size_t)len + 1);
    if (s != NULL) {
        if (len)
            memcpy(s, data, len);
        s[len] = '\0';
    }
    return s;
}

int ln_param_handle(ln_client* clnt, ln_service_request* call, void* user)
{
    (void)clnt;
    ln_parameter_block* b = user;
    ln_parameters_query_request_t req;
    int rc = ln_service_request_get_data(call, &req);
    if (rc != LN_OK)
        return rc;
    char* op = text_of(req.op, req.op_len);
    char* name = text_of(req.name, req.name_len);
    char* value = text_of(req.value, req.value_len);
    ln_pbuf out;
    ln_pbuf_init(&out);
    ln_param_err err = {.kind = "", .code = LN_OK};
    if (op == NULL || name == NULL || value == NULL) {
        ln_param_fail(&err, "bad_request", "out of memory");
    } else {
        ln_param_request(b, op, name, value, &out, &err);
    }
    if (err.code != LN_OK) {
        ln_pbuf_free(&out);
        ln_pbuf_add(&out, "{\"parameter\": ");
        ln_pbuf_quote(&out, name ? name : "", name ? strlen(name) : 0);
        ln_pbuf_add(&out, "}");
    }
    free(op);
    free(name);
    free(value);
    if (out.failed)
        return ln_service_request_respond_error(call, "parameter block: out of memory");
    ln_parameters_query_response_t resp = {
        .status = err.code,
        .error_len = (uint32_t)strlen(err.kind),
        .error = (char*)err.kind,
        .reason_len = err.code != LN_OK ? (uint32_t)strlen(err.reason) : 0,
        .reason = err.reason,
        .result_len = (uint32_t)out.len,
        .result = out.data ? out.data : (char*)"",
    };
    rc = ln_service_request_respond(call, &resp);
    ln_pbuf_free(&out);
    return rc;
}

/* ---- initial overrides ---- */

static void config_error(ln_parameter_block* b, ln_pbuf* errors, const char* text)
{
    fprintf(stderr, "ln: parameter block \"%s\": LN_PARAMETERS: %s\n", b->name, text);
    ln_pbuf_add(errors, "%s", errors->len > 1 ? ", " : "");
    ln_pbuf_quote(errors, text, strlen(text));
}

void ln_param_configure(ln_parameter_block* b)
{
    const char* env = getenv("LN_PARAMETERS");
    if (env == NULL || *ln_pj_ws(env) == '\0')
        return;
    ln_pbuf errors;
    ln_pbuf_init(&errors);
    ln_pbuf_raw(&errors, "[", 1);
    uint8_t* staged = malloc(b->values_size ? b->values_size : 1);
    uint8_t* which = calloc(b->n ? b->n : 1, 1);
    const char* cursor = env;
    int first = 1, more = 0, found = 0;
    char key[LN_PARAMETER_MAX_NAME + 2];
    pthread_mutex_lock(&b->lock);
    if (staged == NULL || which == NULL) {
        config_error(b, &errors, "out of memory");
        goto out;
    }
    if (ln_pj_open(&cursor, '{') != 0) {
        config_error(b, &errors, "not a JSON object {\"BLOCK\": {\"PARAMETER\": VALUE}}");
        goto out;
    }
    while (!found && (more = ln_pj_next_member(&cursor, &first, key, sizeof key)) == 1) {
        if (strcmp(key, b->name) != 0) {
            if (ln_pj_skip(&cursor) != 0)
                break;
            continue;
        }
        found = 1;
        int inner = 1, next;
        if (ln_pj_open(&cursor, '{') != 0) {
            config_error(b, &errors, "the block's entry is not a JSON object");
            goto out;
        }
        while ((next = ln_pj_next_member(&cursor, &inner, key, sizeof key)) == 1) {
            int i = ln_param_find(b, key);
            ln_param_err err;
            char text[LN_PARAM_REASON_MAX + 80];
            if (i < 0) {
                snprintf(text, sizeof text, "no parameter \"%s\"", key);
                config_error(b, &errors, text);
                if (ln_pj_skip(&cursor) != 0)
                    break;
                continue;
            }
            const char* start = cursor;
            if (ln_param_check(b, (uint32_t)i, &cursor, staged + b->params[i].offset, &err) != 0) {
                snprintf(text, sizeof text, "refused: %s", err.reason);
                config_error(b, &errors, text);
                cursor = start;
                if (ln_pj_skip(&cursor) != 0)
                    break;
                continue;
            }
            which[i] = 1;
        }
        if (next != 0)
            config_error(b, &errors, "malformed JSON in the block's entry");
    }
    if (!found && more != 0)
        config_error(b, &errors, "malformed JSON");
out:
    for (uint32_t i = 0; staged != NULL && which != NULL && i < b->n; i++)
        if (which[i]) {
            commit(b, staged, which, "config");
            break;
        }
    pthread_mutex_unlock(&b->lock);
    ln_pbuf_raw(&errors, "]", 1);
    if (errors.len > 2 && !errors.failed) {
        b->config_errors = errors.data;
        errors.data = NULL;
    }
    ln_pbuf_free(&errors);
    free(staged);
    free(which);
}
