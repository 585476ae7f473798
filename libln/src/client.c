/* client.c — the client handle: options and where the manager is, the name to register
 * under, create/destroy, the registry of ports that die with their client (and are
 * re-registered when it reconnects) and the client's copy of its last error.  The manager
 * connection and its reconnect monitor are in client_conn.c. */
#include <assert.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>
#include <netdb.h>
#include <sys/socket.h>

#include "client_conn.h"
#include "svc_internal.h"

#define DEFAULT_TIMEOUT 10.0
#define MAX_ADDRESS LN_CLIENT_MAX_ADDRESS

/* ---- handles, errors, ports ----------------------------------------------------------- */

int ln_client_check(const ln_client* clnt)
{
    if (clnt == NULL || clnt->magic != LN_CLIENT_MAGIC)
        return ln_set_error(NULL, LN_EBADHANDLE, "invalid client handle (NULL or destroyed)");
    return LN_OK;
}

void ln_client_store_error(ln_client* clnt, int code, const char* text)
{
    pthread_mutex_lock(&clnt->state_lock);
    clnt->last_code = code;
    snprintf(clnt->last_error, sizeof clnt->last_error, "%s", text);
    pthread_mutex_unlock(&clnt->state_lock);
}

int ln_client_last_error(const ln_client* clnt, char* text, size_t size)
{
    int rc = ln_client_check(clnt);
    if (rc != LN_OK)
        return rc;
    ln_client* c = (ln_client*)clnt; /* the lock is not part of the logical state */
    pthread_mutex_lock(&c->state_lock);
    rc = c->last_code;
    if (text && size)
        snprintf(text, size, "%s", c->last_error);
    pthread_mutex_unlock(&c->state_lock);
    return rc;
}

pid_t ln_client_pid(const ln_client* clnt)
{
    assert(clnt != NULL);
    return clnt->pid;
}

const char* ln_client_instance(const ln_client* clnt) { return clnt->instance; }

int ln_client_local_host(ln_client* clnt, char* out, size_t size)
{
    struct sockaddr_storage addr;
    socklen_t len = sizeof addr;
    pthread_mutex_lock(&clnt->request_lock);
    int fd = clnt->conn.fd;
    int ok = fd >= 0 && clnt->conn.usable && getsockname(fd, (struct sockaddr*)&addr, &len) == 0 &&
             getnameinfo((struct sockaddr*)&addr, len, out, (socklen_t)size, NULL, 0,
                         NI_NUMERICHOST) == 0;
    pthread_mutex_unlock(&clnt->request_lock);
    return ok ? LN_OK
              : ln_set_error(clnt, LN_ECONNECTION, "client \"%s\" is not connected to its manager",
                             clnt->name);
}

const char* ln_client_name(const ln_client* clnt)
{
    return ln_client_check(clnt) == LN_OK ? clnt->name : NULL;
}

/* Ports lock held: re-register `port` if its registration went out on a connection that is
 * gone while a newer one is up (a port registered just before the manager went away, which
 * the monitor did not see yet when it re-registered the others). */
static void settle(ln_client* clnt, void* port, const ln_client_port_ops* ops, uint64_t gen)
{
    pthread_mutex_lock(&clnt->request_lock);
    if (clnt->conn.usable && gen != clnt->conn_gen)
        ops->reclaim(clnt, port);
    pthread_mutex_unlock(&clnt->request_lock);
}

int ln_client_add_port(ln_client* clnt, void* port, const ln_client_port_ops* ops, uint64_t gen)
{
    assert(clnt != NULL && port != NULL && ops != NULL && ops->close != NULL);
    int rc = LN_OK;
    pthread_mutex_lock(&clnt->ports_lock);
    if (clnt->nports == clnt->ports_cap) {
        size_t cap = clnt->ports_cap ? 2 * clnt->ports_cap : 8;
        struct ln_client_port* ports = realloc(clnt->ports, cap * sizeof *ports);
        if (ports == NULL) {
            rc = LN_ENOMEM;
            goto out;
        }
        clnt->ports = ports;
        clnt->ports_cap = cap;
    }
    clnt->ports[clnt->nports++] = (struct ln_client_port){port, ops};
    settle(clnt, port, ops, gen);
out:
    pthread_mutex_unlock(&clnt->ports_lock);
    return rc ? ln_set_error(clnt, rc, "cannot register a port on client \"%s\": out of memory",
                             clnt->name)
              : LN_OK;
}

void ln_client_lock_ports(ln_client* clnt) { pthread_mutex_lock(&clnt->ports_lock); }

void ln_client_unlock_ports(ln_client* clnt) { pthread_mutex_unlock(&clnt->ports_lock); }

void ln_client_settle_port(ln_client* clnt, void* port, uint64_t gen)
{
    for (size_t i = 0; i < clnt->nports; i++)
        if (clnt->ports[i].port == port)
            settle(clnt, port, clnt->ports[i].ops, gen);
    pthread_mutex_unlock(&clnt->ports_lock);
}

void ln_client_remove_port(ln_client* clnt, void* port)
{
    pthread_mutex_lock(&clnt->ports_lock);
    for (size_t i = clnt->nports; i-- > 0;) {
        if (clnt->ports[i].port == port) {
            memmove(&clnt->ports[i], &clnt->ports[i + 1],
                    (clnt->nports - i - 1) * sizeof clnt->ports[0]);
            clnt->nports--;
            break;
        }
    }
    pthread_mutex_unlock(&clnt->ports_lock);
}

/* ---- where the manager is, who we are --------------------------------------------------- */

void ln_client_options_init(ln_client_options* opts)
{
    if (opts == NULL)
        return;
    memset(opts, 0, sizeof *opts);
    opts->timeout = DEFAULT_TIMEOUT;
}

/* The address text, and where it came from for error texts ("" for the options; then argv,
 * then the environment). */
static int find_manager(const ln_client_options* opts, const char** text, const char** from)
{
    *text = opts->manager;
    *from = "";
    if (*text != NULL && **text != '\0')
        return LN_OK;
    for (int i = 1; opts->argv != NULL && i < opts->argc && opts->argv[i] != NULL; i++) {
        if (strcmp(opts->argv[i], "-ln_manager") != 0)
            continue;
        *text = i + 1 < opts->argc ? opts->argv[i + 1] : NULL;
        *from = " (from -ln_manager)";
        if (*text == NULL || **text == '\0')
            return ln_set_error(NULL, LN_EINVAL, "-ln_manager must be followed by HOST:PORT");
        return LN_OK;
    }
    *text = getenv("LN_MANAGER");
    *from = " (from LN_MANAGER)";
    if (*text != NULL && **text != '\0')
        return LN_OK;
    return ln_set_error(NULL, LN_EINVAL,
                        "no manager address: set ln_client_options.manager, pass "
                        "-ln_manager HOST:PORT on the command line or set LN_MANAGER=HOST:PORT");
}

/* Splits "HOST:PORT", "[V6HOST]:PORT" or ":PORT" (localhost) into host[] and port[]: the
 * rules and texts of Python's links_and_nodes.addresses.parse_manager_address. */
static int parse_address(const char* text, const char* from, char* host, char* port)
{
    size_t len = strlen(text);
    const char* colon = strrchr(text, ':');
    const char* h = text;
    size_t hlen = colon != NULL ? (size_t)(colon - text) : 0;
    int bracketed = hlen >= 2 && text[0] == '[' && text[hlen - 1] == ']';
    if (bracketed) {
        h++;
        hlen -= 2;
    }
    const char* p = colon != NULL ? colon + 1 : "";
    size_t plen = strlen(p);
    long value = plen > 0 && plen <= 5 && strspn(p, "0123456789") == plen ? atol(p) : 0;
    const char* why = NULL;
    if (bracketed && (hlen == 0 || memchr(h, ':', hlen) == NULL))
        why = "brackets are for IPv6 addresses";
    else if (!bracketed && memchr(h, ':', hlen) != NULL)
        why = "an IPv6 address needs brackets, e.g. [::1]:5000";
    else if (strcspn(h, " \t\n\r\v\f") < hlen)
        why = "blanks in the host name";
    else if (len > MAX_ADDRESS || colon == NULL || value < 1 || value > 65535)
        why = "expected HOST:PORT, :PORT or [V6HOST]:PORT with a port 1..65535";
    if (why != NULL)
        return ln_set_error(NULL, LN_EINVAL, "bad manager address \"%.300s\"%s: %s", text, from,
                            why);
    if (hlen == 0) {
        strcpy(host, "localhost");
    } else {
        memcpy(host, h, hlen);
        host[hlen] = '\0';
    }
    snprintf(port, 6, "%ld", value);
    return LN_OK;
}

/* LN_PROGRAM_NAME, else the name asked for, else argv[0] without its directory, else "client". */
static const char* pick_name(const char* name, const ln_client_options* opts)
{
    const char* env = getenv("LN_PROGRAM_NAME");
    if (env != NULL && *env != '\0')
        return env;
    if (name != NULL && *name != '\0')
        return name;
    if (opts->argc > 0 && opts->argv != NULL && opts->argv[0] != NULL) {
        const char* slash = strrchr(opts->argv[0], '/');
        const char* base = slash != NULL ? slash + 1 : opts->argv[0];
        if (*base != '\0')
            return base;
    }
    return "client";
}

/* ---- create / destroy ------------------------------------------------------------------
 * Beyond ln.h: opts == NULL means defaults (address from $LN_MANAGER only); a timeout of 0,
 * which is what a zeroed options struct holds, means the default 10 s, < 0 waits forever.
 * The connect and the HELLO/WELCOME exchange share one deadline.  ln_client_destroy(NULL)
 * is a no-op returning LN_OK, like free(NULL); a destroyed handle is LN_EBADHANDLE as long
 * as its memory has not been reused. */

/* LN_RECONNECT=0 (or no, off, false) turns reconnection off for every client of the process. */
static int reconnect_wanted(const ln_client_options* opts)
{
    if (opts->flags & LN_CLIENT_NO_RECONNECT)
        return 0;
    const char* env = getenv("LN_RECONNECT");
    if (env == NULL)
        return 1;
    return !(strcmp(env, "0") == 0 || strcasecmp(env, "no") == 0 || strcasecmp(env, "off") == 0 ||
             strcasecmp(env, "false") == 0);
}

static void free_client(ln_client* c)
{
    ln_svc_client_free(c);
    ln_conn_close(c);
    free(c->ports);
    pthread_mutex_destroy(&c->ports_lock);
    pthread_mutex_destroy(&c->request_lock);
    pthread_mutex_destroy(&c->state_lock);
    explicit_bzero(c->svc_key, sizeof c->svc_key);
    c->magic = 0; /* a stale handle now fails ln_client_check (while the memory is not reused) */
    free(c);
}

int ln_client_create(ln_client** out, const char* name, const ln_client_options* opts)
{
    if (out == NULL)
        return ln_set_error(NULL, LN_EINVAL, "ln_client_create: out must not be NULL");
    *out = NULL;
    ln_client_options defaults;
    if (opts == NULL) {
        ln_client_options_init(&defaults);
        opts = &defaults;
    }
    if (isnan(opts->timeout))
        return ln_set_error(NULL, LN_EINVAL, "ln_client_create: timeout is NaN");
    const char *text, *from;
    char host[MAX_ADDRESS + 1], port[6];
    int rc = find_manager(opts, &text, &from);
    if (rc == LN_OK)
        rc = parse_address(text, from, host, port);
    if (rc != LN_OK)
        return rc;
    name = pick_name(name, opts);
    size_t name_len = strnlen(name, LN_PROTO_MAX_STR + 1);
    if (name_len > LN_PROTO_MAX_STR || !ln_utf8_valid(name, name_len))
        return ln_set_error(NULL, LN_EINVAL, "client name is over %d bytes or not valid UTF-8",
                            LN_PROTO_MAX_STR);

    ln_client* c = calloc(1, sizeof *c);
    if (c == NULL)
        return ln_set_error(NULL, LN_ENOMEM, "cannot create client \"%s\": out of memory", name);
    c->cancel_fd = -1;
    c->pid = getpid();
    c->timeout = opts->timeout == 0 ? DEFAULT_TIMEOUT : opts->timeout;
    /* Fits: parse_address limits "host:port" to MAX_ADDRESS bytes, and address has room for
     * the brackets.  Using the length also keeps gcc's -Wformat-truncation quiet at -O0. */
    int written = strchr(host, ':') != NULL
                      ? snprintf(c->address, sizeof c->address, "[%s]:%s", host, port)
                      : snprintf(c->address, sizeof c->address, "%s:%s", host, port);
    assert(written > 0 && (size_t)written < sizeof c->address);
    (void)written;
    memcpy(c->host, host, sizeof c->host);
    memcpy(c->port, port, sizeof c->port);
    pthread_mutex_init(&c->ports_lock, NULL);
    pthread_mutex_init(&c->request_lock, NULL);
    pthread_mutex_init(&c->state_lock, NULL);

    rc = ln_conn_open(c, from, name);
    if (rc == LN_OK && reconnect_wanted(opts))
        rc = ln_conn_start_monitor(c);
    if (rc != LN_OK) {
        free_client(c);
        return rc;
    }
    c->magic = LN_CLIENT_MAGIC;
    *out = c;
    return LN_OK;
}

int ln_client_destroy(ln_client* clnt)
{
    if (clnt == NULL)
        return LN_OK; /* like free(NULL) */
    int rc = ln_client_check(clnt);
    if (rc != LN_OK)
        return rc;
    /* What ln_log queued goes out while the connection is still there. */
    ln_log_stop(clnt);
    /* The monitor first: it re-registers ports, which are closed below.  Its connect or
     * re-registration is cut short, so this never waits for a manager that is away. */
    ln_conn_stop_monitor(clnt);
    /* Pool threads next: they run handlers of the providers closed below. */
    ln_svc_client_stop_pools(clnt);
    /* Newest first, and without holding a lock: close talks to the manager and calls
     * ln_client_remove_port. */
    for (;;) {
        pthread_mutex_lock(&clnt->ports_lock);
        struct ln_client_port last = {NULL, NULL};
        if (clnt->nports > 0)
            last = clnt->ports[clnt->nports - 1];
        pthread_mutex_unlock(&clnt->ports_lock);
        if (last.port == NULL)
            break;
        last.ops->close(last.port);
        ln_client_remove_port(clnt, last.port); /* no-op unless close_fn forgot it */
    }
    free_client(clnt);
    return LN_OK;
}
