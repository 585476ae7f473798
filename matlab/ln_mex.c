/* ln_mex.c — the MEX gateway of the MATLAB/GNU Octave client (docs/matlab.md): one function
 * ln_mex(COMMAND, ...) over libln, keeping clients, ports and service handles in a table of
 * numeric ids.  MEX API only (mex.h), so MATLAB's mex and Octave's mkoctfile --mex build it
 * alike; the +ln classes are the interface users see. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <ln/ln.h>

#include "mex.h"
#include "mex_convert.h"
#include "mex_layout.h"

enum kind { FREE, CLIENT, PUBLISHER, SUBSCRIBER, SERVICE };
static const char* const KIND_NAMES[] = {"closed", "client", "publisher", "subscriber", "service"};

typedef struct entry {
    enum kind kind;
    void* ptr;
    size_t client;    /* id of the owning client (ports, services) */
    lnm_node* lay[2]; /* ports: the md; services: request, response */
    void* buf;        /* subscribers: the read buffer; services: the response */
} entry;

static entry* table; /* table[id - 1]; ids are never reused */
static size_t table_len, table_cap;
static int registered_exit;

static void fail_ln(int code, const char* what)
{
    const char* name = ln_error_name(code);
    char id[48];
    snprintf(id, sizeof id, "ln:%s", name ? name : "error");
    mexErrMsgIdAndTxt(id, "%s: %s (%s)", what, ln_strerror(code), ln_last_error());
}

static void release(entry* e)
{
    switch (e->kind) {
    case PUBLISHER:
        ln_unpublish(e->ptr);
        break;
    case SUBSCRIBER:
        ln_unsubscribe(e->ptr);
        break;
    case SERVICE:
        ln_service_release(e->ptr);
        break;
    case CLIENT:
        ln_client_destroy(e->ptr);
        break;
    case FREE:
        break;
    }
    lnm_layout_free(e->lay[0]);
    lnm_layout_free(e->lay[1]);
    free(e->buf);
    memset(e, 0, sizeof *e);
}

/* Closes id and, for a client, every handle it owns first. */
static int close_id(size_t id)
{
    if (id < 1 || id > table_len || table[id - 1].kind == FREE)
        return 0;
    if (table[id - 1].kind == CLIENT)
        for (size_t i = 0; i < table_len; i++)
            if (table[i].kind != FREE && table[i].kind != CLIENT && table[i].client == id)
                release(&table[i]);
    release(&table[id - 1]);
    return 1;
}

static void at_exit(void)
{
    for (size_t i = 0; i < table_len; i++)
        if (table[i].kind == CLIENT)
            close_id(i + 1);
    free(table);
    table = NULL;
    table_len = table_cap = 0;
}

static size_t add_entry(const entry* e)
{
    if (table_len == table_cap) {
        size_t cap = table_cap ? table_cap * 2 : 16;
        entry* grown = realloc(table, cap * sizeof *grown);
        if (grown == NULL)
            return 0;
        table = grown;
        table_cap = cap;
    }
    table[table_len++] = *e;
    return table_len;
}

/* ---- arguments ---------------------------------------------------------------------------- */
static char* arg_string(const mxArray* a, const char* what)
{
    if (!mxIsChar(a))
        mexErrMsgIdAndTxt("ln:usage", "%s must be char", what);
    return mxArrayToString(a); /* mxMalloc'd: freed when the call returns */
}

static double arg_double(const mxArray* a, const char* what)
{
    if (!mxIsNumeric(a) || mxGetNumberOfElements(a) != 1 || mxIsComplex(a))
        mexErrMsgIdAndTxt("ln:usage", "%s must be a real number", what);
    return mxGetScalar(a);
}

static entry* arg_handle(const mxArray* a, enum kind kind)
{
    double d = arg_double(a, "the handle");
    size_t id = d >= 1 && d == floor(d) && d <= (double)table_len ? (size_t)d : 0;
    if (id == 0 || table[id - 1].kind != kind)
        mexErrMsgIdAndTxt("ln:EBADHANDLE", "not an open %s (handle %g%s%s)", KIND_NAMES[kind], d,
                          id ? " is a " : "", id ? KIND_NAMES[table[id - 1].kind] : "");
    return &table[id - 1];
}

static void need(int nrhs, int n, const char* usage)
{
    if (nrhs != n)
        mexErrMsgIdAndTxt("ln:usage", "usage: ln_mex(%s)", usage);
}

static mxArray* scalar(double v) { return mxCreateDoubleScalar(v); }

/* Parses a section's layout; a layout error is the manager's or the md's fault, named so. */
static lnm_node* layout(const mxArray* sig, const mxArray* names, const mxArray* size,
                        const char* md)
{
    char err[256];
    lnm_node* node = NULL;
    char* s = arg_string(sig, "the signature");
    char* n = arg_string(names, "the field names");
    double want = arg_double(size, "the size");
    if (lnm_layout_parse(s, n, &node, err, sizeof err) < 0)
        mexErrMsgIdAndTxt("ln:EMD", "md %s: %s", md, err);
    if ((double)node->elem_size != want) {
        size_t got = node->elem_size;
        lnm_layout_free(node);
        mexErrMsgIdAndTxt("ln:EMD", "md %s: the signature gives %zu bytes, the manager %g", md, got,
                          want);
    }
    return node;
}

static uint64_t parse_hash(const mxArray* a)
{
    char* text = arg_string(a, "the layout hash");
    char* end = NULL;
    uint64_t h = strtoull(text, &end, 16);
    if (end == text || *end != '\0')
        mexErrMsgIdAndTxt("ln:usage", "bad layout hash %s", text);
    return h;
}

/* ---- commands ----------------------------------------------------------------------------- */
static void cmd_create(int nlhs, mxArray** plhs, int nrhs, const mxArray** prhs)
{
    (void)nlhs;
    need(nrhs, 3, "'create', NAME, MANAGER");
    char* name = arg_string(prhs[1], "the client name");
    char* manager = arg_string(prhs[2], "the manager address");
    ln_client_options opts;
    ln_client_options_init(&opts);
    opts.manager = manager[0] ? manager : NULL;
    ln_client* clnt = NULL;
    int rc = ln_client_create(&clnt, name, &opts);
    if (rc < 0)
        fail_ln(rc, "ln.Client");
    entry e = {CLIENT, clnt, 0, {NULL, NULL}, NULL};
    size_t id = add_entry(&e);
    if (id == 0) {
        ln_client_destroy(clnt);
        mexErrMsgIdAndTxt("ln:ENOMEM", "out of memory");
    }
    plhs[0] = scalar((double)id);
}

static void cmd_port(int nlhs, mxArray** plhs, int nrhs, const mxArray** prhs, int publish)
{
    (void)nlhs;
    need(nrhs, 9,
         "'publish'|'subscribe', CLIENT, TOPIC, MD, HASH, SIGNATURE, SIZE, NAMES, "
         "BUFFERS");
    entry* c = arg_handle(prhs[1], CLIENT);
    size_t client = (size_t)(c - table) + 1;
    char* topic = arg_string(prhs[2], "the topic");
    char* md = arg_string(prhs[3], "the md name");
    uint64_t hash = parse_hash(prhs[4]);
    double buffers = arg_double(prhs[8], "buffers");
    if (buffers < 1 || buffers > 1024 || buffers != floor(buffers))
        mexErrMsgIdAndTxt("ln:usage", "buffers must be a whole number in 1..1024");
    lnm_node* lay = layout(prhs[5], prhs[7], prhs[6], md);
    if (lnm_layout_has_dynamic(lay)) {
        lnm_layout_free(lay);
        mexErrMsgIdAndTxt("ln:EMD", "md %s has dynamic fields: a topic cannot carry them", md);
    }
    ln_port_options opts;
    ln_port_options_init(&opts);
    opts.buffers = (uint32_t)buffers;
    entry e = {publish ? PUBLISHER : SUBSCRIBER, NULL, client, {lay, NULL}, NULL};
    int rc;
    if (publish) {
        rc = ln_publish(c->ptr, (ln_outport**)&e.ptr, topic, md, hash, lay->elem_size, &opts);
    } else {
        e.buf = calloc(1, lay->elem_size ? lay->elem_size : 1);
        rc = e.buf
                 ? ln_subscribe(c->ptr, (ln_inport**)&e.ptr, topic, md, hash, lay->elem_size, &opts)
                 : LN_ENOMEM;
    }
    if (rc < 0) {
        release(&e); /* kind set, ptr NULL: frees the layout and buffer only */
        char what[300];
        snprintf(what, sizeof what, "%s %s (md %s)", publish ? "publish" : "subscribe", topic, md);
        fail_ln(rc, what);
    }
    size_t id = add_entry(&e);
    if (id == 0) {
        release(&e);
        mexErrMsgIdAndTxt("ln:ENOMEM", "out of memory");
    }
    plhs[0] = scalar((double)id);
}

static void cmd_write(int nlhs, mxArray** plhs, int nrhs, const mxArray** prhs)
{
    (void)nlhs;
    (void)plhs;
    need(nrhs, 4, "'write', PUBLISHER, SAMPLE, TIMEOUT");
    entry* p = arg_handle(prhs[1], PUBLISHER);
    double timeout = arg_double(prhs[3], "the timeout");
    void* data = mxMalloc(p->lay[0]->elem_size ? p->lay[0]->elem_size : 1);
    lnm_pack(p->lay[0], prhs[2], data, "sample");
    int rc = ln_write(p->ptr, data, p->lay[0]->elem_size, timeout);
    if (rc < 0)
        fail_ln(rc, "write");
}

static void cmd_read(int nlhs, mxArray** plhs, int nrhs, const mxArray** prhs)
{
    need(nrhs, 3, "'read', SUBSCRIBER, TIMEOUT");
    entry* s = arg_handle(prhs[1], SUBSCRIBER);
    double timeout = arg_double(prhs[2], "the timeout");
    ln_sample_info info;
    int rc = ln_read(s->ptr, s->buf, s->lay[0]->elem_size, timeout, &info);
    if (rc == LN_ETIMEOUT || rc == LN_EAGAIN) {
        plhs[0] = mxCreateDoubleMatrix(0, 0, mxREAL);
        if (nlhs > 1)
            plhs[1] = mxCreateDoubleMatrix(0, 0, mxREAL);
        return;
    }
    if (rc < 0)
        fail_ln(rc, "read");
    plhs[0] = lnm_unpack(s->lay[0], s->buf);
    if (nlhs > 1) {
        static const char* fields[] = {"seq", "timestamp", "overruns"};
        mxArray* i = mxCreateStructMatrix(1, 1, 3, fields);
        mxSetField(i, 0, "seq", scalar((double)info.seq));
        mxSetField(i, 0, "timestamp", scalar((double)info.timestamp_ns * 1e-9));
        mxSetField(i, 0, "overruns", scalar((double)info.overruns));
        plhs[1] = i;
    }
}

static void cmd_service(int nlhs, mxArray** plhs, int nrhs, const mxArray** prhs)
{
    (void)nlhs;
    need(nrhs, 12,
         "'service', CLIENT, NAME, MD, HASH, SIGNATURE, REQ_SIG, REQ_SIZE, "
         "REQ_NAMES, RESP_SIG, RESP_SIZE, RESP_NAMES");
    entry* c = arg_handle(prhs[1], CLIENT);
    size_t client = (size_t)(c - table) + 1;
    char* name = arg_string(prhs[2], "the service name");
    char* md = arg_string(prhs[3], "the md name");
    uint64_t hash = parse_hash(prhs[4]);
    char* signature = arg_string(prhs[5], "the signature");
    lnm_node* req = layout(prhs[6], prhs[8], prhs[7], md);
    entry e = {SERVICE, NULL, client, {req, NULL}, NULL};
    char err[256];
    char* rs = arg_string(prhs[9], "the response signature");
    char* rn = arg_string(prhs[11], "the response field names");
    double rsize = arg_double(prhs[10], "the response size");
    int rc = lnm_layout_parse(rs, rn, &e.lay[1], err, sizeof err);
    if (rc < 0 || (double)e.lay[1]->elem_size != rsize) {
        release(&e);
        mexErrMsgIdAndTxt("ln:EMD", "md %s: response: %s", md,
                          rc < 0 ? err : "the signature and the manager disagree on the size");
    }
    e.buf = calloc(1, e.lay[1]->elem_size ? e.lay[1]->elem_size : 1);
    rc =
        e.buf ? ln_get_service(c->ptr, (ln_service**)&e.ptr, name, md, hash, signature) : LN_ENOMEM;
    if (rc < 0) {
        release(&e);
        fail_ln(rc, "service");
    }
    size_t id = add_entry(&e);
    if (id == 0) {
        release(&e);
        mexErrMsgIdAndTxt("ln:ENOMEM", "out of memory");
    }
    plhs[0] = scalar((double)id);
}

static void cmd_call(int nlhs, mxArray** plhs, int nrhs, const mxArray** prhs)
{
    (void)nlhs;
    need(nrhs, 4, "'call', SERVICE, REQUEST, TIMEOUT");
    entry* s = arg_handle(prhs[1], SERVICE);
    double timeout = arg_double(prhs[3], "the timeout");
    void* request = mxMalloc(s->lay[0]->elem_size ? s->lay[0]->elem_size : 1);
    lnm_pack(s->lay[0], prhs[2], request, "request");
    int rc = ln_service_call(s->ptr, request, s->buf, timeout);
    if (rc < 0)
        fail_ln(rc, "call");
    plhs[0] = lnm_unpack(s->lay[1], s->buf);
}

/* An all-zero sample of a port (section 0) or a service's request/response (0/1). */
static void cmd_zero(int nlhs, mxArray** plhs, int nrhs, const mxArray** prhs)
{
    (void)nlhs;
    need(nrhs, 3, "'zero', HANDLE, SECTION");
    double d = arg_double(prhs[1], "the handle");
    size_t id = d >= 1 && d == floor(d) && d <= (double)table_len ? (size_t)d : 0;
    int section = arg_double(prhs[2], "the section") != 0;
    if (id == 0 || table[id - 1].lay[section] == NULL)
        mexErrMsgIdAndTxt("ln:EBADHANDLE", "handle %g has no such md section", d);
    lnm_node* lay = table[id - 1].lay[section];
    void* zero = mxCalloc(1, lay->elem_size ? lay->elem_size : 1);
    plhs[0] = lnm_unpack(lay, zero);
}

static void cmd_control(int nlhs, mxArray** plhs, int nrhs, const mxArray** prhs)
{
    (void)nlhs;
    need(nrhs, 3, "'control', CLIENT, JSON");
    entry* c = arg_handle(prhs[1], CLIENT);
    char* command = arg_string(prhs[2], "the command");
    char* result = NULL;
    int rc = ln_control(c->ptr, command, &result);
    if (rc < 0)
        fail_ln(rc, "control");
    plhs[0] = mxCreateString(result ? result : "");
    ln_free(result);
}

static void cmd_info(int nlhs, mxArray** plhs, int nrhs, const mxArray** prhs, const char* cmd)
{
    (void)nlhs;
    if (strcmp(cmd, "close") == 0) {
        need(nrhs, 2, "'close', HANDLE");
        double d = arg_double(prhs[1], "the handle");
        plhs[0] = mxCreateLogicalScalar(d >= 1 && d == floor(d) && close_id((size_t)d));
    } else if (strcmp(cmd, "name") == 0) {
        need(nrhs, 2, "'name', CLIENT");
        plhs[0] = mxCreateString(ln_client_name(arg_handle(prhs[1], CLIENT)->ptr));
    } else if (strcmp(cmd, "handles") == 0) {
        size_t open = 0;
        for (size_t i = 0; i < table_len; i++)
            open += table[i].kind != FREE;
        plhs[0] = scalar((double)open);
    } else if (strcmp(cmd, "version") == 0) {
        plhs[0] = mxCreateString(ln_version());
    } else if (strcmp(cmd, "count") == 0) {
        need(nrhs, 2, "'count', PORT");
        double d = arg_double(prhs[1], "the handle");
        size_t id = d >= 1 && d == floor(d) && d <= (double)table_len ? (size_t)d : 0;
        if (id && table[id - 1].kind == PUBLISHER)
            plhs[0] = scalar(ln_outport_subscriber_count(table[id - 1].ptr));
        else
            plhs[0] = scalar(ln_inport_publisher_count(arg_handle(prhs[1], SUBSCRIBER)->ptr));
    } else {
        mexErrMsgIdAndTxt("ln:usage", "ln_mex: unknown command '%s'", cmd);
    }
}

void mexFunction(int nlhs, mxArray* plhs[], int nrhs, const mxArray* prhs[])
{
    if (!registered_exit) {
        mexAtExit(at_exit);
        registered_exit = 1;
    }
    if (nrhs < 1 || !mxIsChar(prhs[0]))
        mexErrMsgIdAndTxt("ln:usage", "usage: ln_mex(COMMAND, ...); see docs/matlab.md");
    char cmd[16];
    if (mxGetString(prhs[0], cmd, sizeof cmd) != 0)
        cmd[0] = '\0';
    if (strcmp(cmd, "write") == 0)
        cmd_write(nlhs, plhs, nrhs, prhs);
    else if (strcmp(cmd, "read") == 0)
        cmd_read(nlhs, plhs, nrhs, prhs);
    else if (strcmp(cmd, "call") == 0)
        cmd_call(nlhs, plhs, nrhs, prhs);
    else if (strcmp(cmd, "create") == 0)
        cmd_create(nlhs, plhs, nrhs, prhs);
    else if (strcmp(cmd, "publish") == 0)
        cmd_port(nlhs, plhs, nrhs, prhs, 1);
    else if (strcmp(cmd, "subscribe") == 0)
        cmd_port(nlhs, plhs, nrhs, prhs, 0);
    else if (strcmp(cmd, "service") == 0)
        cmd_service(nlhs, plhs, nrhs, prhs);
    else if (strcmp(cmd, "zero") == 0)
        cmd_zero(nlhs, plhs, nrhs, prhs);
    else if (strcmp(cmd, "control") == 0)
        cmd_control(nlhs, plhs, nrhs, prhs);
    else
        cmd_info(nlhs, plhs, nrhs, prhs, cmd);
}
