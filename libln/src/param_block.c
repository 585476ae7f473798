/* param_block.c — the parameter block handle (ln.h, "parameter blocks"): creating it, adding
 * parameters, registering its service, destroying it with or without its client, and the
 * loop's lock-free update (param_internal.h explains the triple buffer and the reports). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "client_internal.h"
#include "param_internal.h"
#include "param_messages.h"
#include "bell.h"
#include "waitset_internal.h"

static int block_check(const ln_parameter_block* b)
{
    if (b == NULL || b->magic != LN_PARAM_MAGIC)
        return ln_set_error(NULL, LN_EBADHANDLE, "invalid parameter block handle");
    return LN_OK;
}

static int name_ok(const char* name, const char* extra)
{
    size_t len = name != NULL ? strlen(name) : 0;
    if (len == 0 || len > LN_PARAMETER_MAX_NAME)
        return 0;
    for (size_t i = 0; i < len; i++) {
        char c = name[i];
        if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
              c == '_' || strchr(extra, c) != NULL))
            return 0;
    }
    return 1;
}

int ln_param_find(const ln_parameter_block* b, const char* name)
{
    for (uint32_t i = 0; i < b->n; i++)
        if (strcmp(b->params[i].name, name) == 0)
            return (int)i;
    return -1;
}

/* ---- lifetime ---- */

static void block_free(ln_parameter_block* b)
{
    ln_waitset_forget(b->ws, atomic_load_explicit(&b->bell_tag, memory_order_relaxed), b);
    for (uint32_t i = 0; i < b->n; i++)
        free(b->params[i].description);
    free(b->params);
    free(b->rt);
    free(b->values);
    free(b->defaults);
    free(b->known_in);
    free(b->known_out);
    free(b->report_in);
    free(b->report_out);
    free(b->config_errors);
    ln_param_history_free(b);
    for (int i = 0; i < 3; i++) {
        free(b->snaps[i].gens);
        free(b->snaps[i].overridden);
        free(b->snaps[i].values);
    }
    pthread_mutex_destroy(&b->lock);
    b->magic = 0;
    free(b);
}

static void block_close_fn(void* b) { ln_parameter_block_destroy(b); }

static int block_reclaim(ln_client* clnt, void* b)
{
    (void)clnt;
    (void)b;
    return LN_OK; /* its provider registers itself again */
}

static const ln_client_port_ops block_ops = {block_close_fn, block_reclaim};

ln_parameter_block* ln_param_new(ln_client* clnt, const char* name, const char* service)
{
    ln_parameter_block* b = calloc(1, sizeof *b);
    if (b == NULL)
        return NULL;
    b->clnt = clnt;
    snprintf(b->name, sizeof b->name, "%s", name);
    snprintf(b->service, sizeof b->service, "%s", service);
    pthread_mutex_init(&b->lock, NULL);
    b->front = 0;
    atomic_init(&b->middle, 1u);
    b->back = 2;
    atomic_init(&b->updates, 0);
    atomic_init(&b->applied_gen, 0);
    atomic_init(&b->report_state, LN_REPORT_IDLE);
    b->magic = LN_PARAM_MAGIC;
    return b;
}

int ln_parameter_block_create(ln_client* clnt, ln_parameter_block** out, const char* name)
{
    int rc = ln_client_check(clnt);
    if (rc != LN_OK)
        return rc;
    if (out == NULL)
        return ln_set_error(clnt, LN_EINVAL, "ln_parameter_block_create: out must not be NULL");
    *out = NULL;
    if (!name_ok(name, "-"))
        return ln_set_error(clnt, LN_EINVAL,
                            "parameter block name \"%.80s\" must be 1..%d "
                            "bytes of A-Z a-z 0-9 _ -",
                            name ? name : "(null)", LN_PARAMETER_MAX_NAME);
    /* The service name: the client's name with what service names do not allow replaced. */
    char service[256];
    int n = snprintf(service, sizeof service, "%s.parameters.%s", ln_client_name(clnt), name);
    if (n < 0 || (size_t)n >= sizeof service)
        return ln_set_error(clnt, LN_EINVAL,
                            "parameter block \"%s\": the service name "
                            "\"<client>.parameters.%s\" is over 255 bytes",
                            name, name);
    for (char* c = service; *c; c++)
        if (!((*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') || (*c >= '0' && *c <= '9') ||
              strchr("_.:/-", *c) != NULL))
            *c = '_';
    ln_parameter_block* b = ln_param_new(clnt, name, service);
    if (b == NULL)
        return ln_set_error(clnt, LN_ENOMEM, "out of memory for parameter block \"%s\"", name);
    rc = ln_client_add_port(clnt, b, &block_ops, 0);
    if (rc != LN_OK) {
        block_free(b);
        return rc;
    }
    *out = b;
    return LN_OK;
}

int ln_parameter_block_destroy(ln_parameter_block* b)
{
    int rc = block_check(b);
    if (rc != LN_OK)
        return rc;
    if (b->provider != NULL) { /* waits for a request being handled */
        rc = ln_unregister_service_provider(b->provider);
        if (rc != LN_OK)
            return rc;
        b->provider = NULL;
    }
    if (b->clnt != NULL)
        ln_client_remove_port(b->clnt, b);
    block_free(b);
    return LN_OK;
}

/* ---- setting up ---- */

int ln_parameter_block_add(ln_parameter_block* b, const ln_parameter_desc* d)
{
    int rc = block_check(b);
    if (rc != LN_OK)
        return rc;
    if (d == NULL)
        return ln_set_error(b->clnt, LN_EINVAL, "ln_parameter_block_add: desc is NULL");
    const char* what = b->name;
    if (b->registered)
        return ln_set_error(b->clnt, LN_EBUSY,
                            "parameter block \"%s\": add parameters before "
                            "registering",
                            what);
    if (!name_ok(d->name, ".-"))
        return ln_set_error(b->clnt, LN_EINVAL,
                            "parameter block \"%s\": parameter name "
                            "\"%.80s\" must be 1..%d bytes of A-Z a-z 0-9 _ . -",
                            what, d->name ? d->name : "(null)", LN_PARAMETER_MAX_NAME);
    const ln_param_type* t = ln_param_type_find(d->type);
    if (t == NULL)
        return ln_set_error(b->clnt, LN_EINVAL,
                            "parameter \"%s\": \"%.80s\" is not an md "
                            "primitive type (char, int8_t .. uint64_t, float, double)",
                            d->name, d->type ? d->type : "(null)");
    uint32_t count = d->count ? d->count : 1;
    if (count > LN_PARAM_MAX_COUNT)
        return ln_set_error(b->clnt, LN_EINVAL,
                            "parameter \"%s\": %u elements are over the "
                            "limit of %u",
                            d->name, count, LN_PARAM_MAX_COUNT);
    if (d->output == NULL)
        return ln_set_error(b->clnt, LN_EINVAL, "parameter \"%s\": output is NULL", d->name);
    if (d->flags & ~(LN_PARAMETER_MIN | LN_PARAMETER_MAX | LN_PARAMETER_READ_ONLY))
        return ln_set_error(b->clnt, LN_EINVAL, "parameter \"%s\": unknown flags 0x%x", d->name,
                            d->flags);
    if ((d->flags & (LN_PARAMETER_MIN | LN_PARAMETER_MAX)) && t->kind == LN_PK_CHAR)
        return ln_set_error(b->clnt, LN_EINVAL,
                            "parameter \"%s\": a char parameter has no "
                            "range",
                            d->name);
    if (((d->flags & LN_PARAMETER_MIN) && isnan(d->min)) ||
        ((d->flags & LN_PARAMETER_MAX) && isnan(d->max)) ||
        ((d->flags & LN_PARAMETER_MIN) && (d->flags & LN_PARAMETER_MAX) && d->min > d->max))
        return ln_set_error(b->clnt, LN_EINVAL,
                            "parameter \"%s\": min %g and max %g are no "
                            "range",
                            d->name, d->min, d->max);
    if (ln_param_find(b, d->name) >= 0)
        return ln_set_error(b->clnt, LN_EEXIST,
                            "parameter block \"%s\" has a parameter \"%s\" "
                            "already",
                            what, d->name);
    size_t size = t->size * count;
    size_t offset = (b->values_size + 7) & ~(size_t)7;
    if (offset + size > LN_PARAM_MAX_BYTES)
        return ln_set_error(b->clnt, LN_ELIMIT,
                            "parameter block \"%s\": its values are over "
                            "%zu bytes",
                            what, LN_PARAM_MAX_BYTES);
    if (b->n == b->cap) {
        uint32_t cap = b->cap ? 2 * b->cap : 8;
        ln_param* params = realloc(b->params, cap * sizeof *params);
        if (params != NULL)
            b->params = params;
        ln_param_rt* rt = params ? realloc(b->rt, cap * sizeof *rt) : NULL;
        if (rt == NULL)
            return ln_set_error(b->clnt, LN_ENOMEM, "out of memory for parameter \"%s\"", d->name);
        b->rt = rt;
        b->cap = cap;
    }
    uint8_t* defaults = realloc(b->defaults, offset + size);
    if (defaults == NULL)
        return ln_set_error(b->clnt, LN_ENOMEM, "out of memory for parameter \"%s\"", d->name);
    b->defaults = defaults;
    memcpy(defaults + offset, d->input != NULL ? d->input : d->output, size);
    ln_param* p = &b->params[b->n];
    memset(p, 0, sizeof *p);
    snprintf(p->name, sizeof p->name, "%s", d->name);
    p->type = t;
    p->count = count;
    p->flags = d->flags;
    p->size = size;
    p->offset = offset;
    p->min = d->min;
    p->max = d->max;
    p->has_input = d->input != NULL;
    p->description = strdup(d->description ? d->description : "");
    if (p->description == NULL)
        return ln_set_error(b->clnt, LN_ENOMEM, "out of memory for parameter \"%s\"", d->name);
    b->rt[b->n] =
        (ln_param_rt){.input = d->input, .output = d->output, .size = size, .offset = offset};
    b->values_size = offset + size;
    return (int)b->n++;
}

int ln_parameter_block_set_validator(ln_parameter_block* b, ln_parameter_validator validator,
                                     void* user_data)
{
    int rc = block_check(b);
    if (rc != LN_OK)
        return rc;
    if (b->registered)
        return ln_set_error(b->clnt, LN_EBUSY,
                            "parameter block \"%s\": set the validator "
                            "before registering",
                            b->name);
    b->validator = validator;
    b->validator_user = user_data;
    return LN_OK;
}

static int allocate(ln_parameter_block* b)
{
    size_t size = b->values_size ? b->values_size : 1, n = b->n ? b->n : 1;
    uint8_t** areas[] = {&b->values, &b->known_in, &b->known_out, &b->report_in, &b->report_out};
    for (size_t i = 0; i < LN_ARRAY_SIZE(areas); i++)
        if ((*areas[i] = calloc(1, size)) == NULL)
            return LN_ENOMEM;
    for (int i = 0; i < 3; i++) {
        ln_param_snap* s = &b->snaps[i];
        s->gens = calloc(n, sizeof *s->gens);
        s->overridden = calloc(n, 1);
        s->values = calloc(1, size);
        if (s->gens == NULL || s->overridden == NULL || s->values == NULL)
            return LN_ENOMEM;
    }
    /* What get shows before the loop's first report: what its first update() will write
     * (initial overrides aside). */
    for (uint32_t i = 0; i < b->n; i++) {
        const ln_param_rt* r = &b->rt[i];
        const void* now = r->input ? r->input : b->defaults + r->offset;
        memcpy(b->known_out + r->offset, now, r->size);
        memcpy(b->known_in + r->offset, now, r->size);
    }
    return LN_OK;
}

int ln_param_prepare(ln_parameter_block* b)
{
    if (b->registered)
        return ln_set_error(b->clnt, LN_EBUSY, "parameter block \"%s\" is registered already",
                            b->name);
    if (allocate(b) != LN_OK)
        return ln_set_error(b->clnt, LN_ENOMEM, "out of memory for parameter block \"%s\"",
                            b->name);
    b->registered = 1;
    ln_param_configure(b); /* nobody else can reach the block yet */
    return LN_OK;
}

int ln_parameter_block_register(ln_parameter_block* b)
{
    int rc = block_check(b);
    if (rc == LN_OK && b->clnt == NULL)
        rc = ln_set_error(NULL, LN_EINVAL, "parameter block \"%s\" has no client", b->name);
    if (rc == LN_OK && b->provider != NULL)
        rc = ln_set_error(b->clnt, LN_EBUSY, "parameter block \"%s\" is registered already",
                          b->name);
    if (rc == LN_OK && !b->registered) /* a failed register is tried again from here */
        rc = ln_param_prepare(b);
    if (rc != LN_OK)
        return rc;
    ln_service_provider* prov = NULL;
    rc = ln_get_service_provider(b->clnt, &prov, b->service, LN_PARAMETERS_QUERY_SERVICE);
    if (rc == LN_OK)
        rc = ln_service_provider_set_handler(prov, ln_param_handle, b);
    if (rc == LN_OK)
        rc = ln_handle_service_group_in_thread_pool(b->clnt, LN_PARAM_GROUP, LN_PARAM_GROUP);
    if (rc == LN_OK)
        rc = ln_service_provider_register(prov, LN_PARAM_GROUP);
    if (rc != LN_OK) {
        int code = rc;
        char text[LN_ERROR_TEXT_MAX];
        snprintf(text, sizeof text, "%s", ln_last_error());
        if (prov != NULL)
            ln_unregister_service_provider(prov);
        return ln_set_error(b->clnt, code, "parameter block \"%s\": %s", b->name, text);
    }
    /* Last on the client, so ln_client_destroy closes it before its provider. */
    ln_client_remove_port(b->clnt, b);
    rc = ln_client_add_port(b->clnt, b, &block_ops, 0);
    b->provider = prov;
    return rc;
}

const char* ln_parameter_block_service_name(const ln_parameter_block* b)
{
    return block_check(b) == LN_OK ? b->service : NULL;
}

/* ---- the service side hands over ---- */

void ln_param_publish(ln_parameter_block* b)
{
    ln_param_snap* s = &b->snaps[b->back];
    for (uint32_t i = 0; i < b->n; i++) {
        s->gens[i] = b->params[i].gen;
        s->overridden[i] = (uint8_t)b->params[i].overridden;
    }
    memcpy(s->values, b->values, b->values_size);
    uint32_t old =
        atomic_exchange_explicit(&b->middle, b->back | LN_PARAM_DIRTY, memory_order_seq_cst);
    b->back = old & 3u;
    uint64_t bell = atomic_load_explicit(&b->bell, memory_order_seq_cst);
    if (bell != 0)
        ln_bell_ring(bell, atomic_load_explicit(&b->bell_tag, memory_order_relaxed));
}

/* ---- waitsets (waitset_internal.h) ---- */

int ln_param_check_handle(const ln_parameter_block* b, const char* what)
{
    if (b == NULL || b->magic != LN_PARAM_MAGIC)
        return ln_set_error(NULL, LN_EBADHANDLE, "%s: invalid parameter block handle", what);
    return LN_OK;
}

int ln_param_bell(ln_parameter_block* b, ln_waitset* ws, uint32_t id, uint64_t bell)
{
    pthread_mutex_lock(&b->lock);
    int rc = LN_OK;
    if (ws != NULL && b->ws != NULL && b->ws != ws)
        rc = ln_set_error(NULL, LN_EBUSY, "parameter block '%s' is attached to another waitset",
                          b->name);
    else {
        b->ws = ws;
        atomic_store_explicit(&b->bell_tag, id, memory_order_relaxed);
        atomic_store_explicit(&b->bell, ws != NULL ? bell : 0, memory_order_seq_cst);
    }
    pthread_mutex_unlock(&b->lock);
    return rc;
}

int ln_param_pending(const ln_parameter_block* b)
{
    return (atomic_load_explicit(&b->middle, memory_order_seq_cst) & LN_PARAM_DIRTY) != 0;
}

/* ---- the loop ---- */

int ln_parameter_block_update(ln_parameter_block* b)
{
    if (b == NULL || b->magic != LN_PARAM_MAGIC)
        return LN_EBADHANDLE; /* no error text: that would format on the loop's thread */
    int changed = 0;
    if (b->rt_any_changed) {
        for (uint32_t i = 0; i < b->n; i++)
            b->rt[i].changed = 0;
        b->rt_any_changed = 0;
    }
    if (atomic_load_explicit(&b->middle, memory_order_acquire) & LN_PARAM_DIRTY) {
        uint32_t old = atomic_exchange_explicit(&b->middle, b->front, memory_order_acq_rel);
        b->front = old & 3u;
        const ln_param_snap* s = &b->snaps[b->front];
        uint64_t newest = 0;
        for (uint32_t i = 0; i < b->n; i++) {
            ln_param_rt* r = &b->rt[i];
            if (s->gens[i] > newest)
                newest = s->gens[i];
            if (s->gens[i] == r->gen)
                continue;
            r->gen = s->gens[i];
            r->overridden = s->overridden[i];
            r->changed = 1;
            changed++;
            if (r->input == NULL) /* written only when it changes */
                memcpy(r->output, r->overridden ? s->values + r->offset : b->defaults + r->offset,
                       r->size);
        }
        b->rt_any_changed = changed > 0;
        atomic_store_explicit(&b->applied_gen, newest, memory_order_release);
    }
    const uint8_t* values = b->snaps[b->front].values;
    for (uint32_t i = 0; i < b->n; i++) {
        const ln_param_rt* r = &b->rt[i];
        if (r->input != NULL)
            memcpy(r->output, r->overridden ? values + r->offset : r->input, r->size);
    }
    uint64_t count = ++b->rt_updates;
    atomic_store_explicit(&b->updates, count, memory_order_relaxed);
    if (atomic_load_explicit(&b->report_state, memory_order_relaxed) == LN_REPORT_REQUESTED) {
        uint32_t expected = LN_REPORT_REQUESTED;
        if (atomic_compare_exchange_strong_explicit(&b->report_state, &expected, LN_REPORT_WRITING,
                                                    memory_order_acquire, memory_order_relaxed)) {
            for (uint32_t i = 0; i < b->n; i++) {
                const ln_param_rt* r = &b->rt[i];
                memcpy(b->report_out + r->offset, r->output, r->size);
                memcpy(b->report_in + r->offset, r->input ? r->input : b->defaults + r->offset,
                       r->size);
            }
            b->report_update = count;
            atomic_store_explicit(&b->report_state, LN_REPORT_DONE, memory_order_release);
        }
    }
    return changed;
}

int ln_parameter_block_changed(const ln_parameter_block* b, int index)
{
    if (b == NULL || b->magic != LN_PARAM_MAGIC)
        return LN_EBADHANDLE;
    if (index < 0 || (uint32_t)index >= b->n)
        return LN_EINVAL;
    return b->rt[index].changed;
}
