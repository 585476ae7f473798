/* svc_group.c — service groups and who handles them: each group is an epoll set of its
 * providers' endpoints (listening sockets and caller connections); a thread calling
 * ln_wait_and_handle_service_group_requests, or the threads of a pool, take events from it and
 * handle them.  See svc_internal.h for the locking rules. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "client_conn.h"
#include "net.h"
#include "svc_internal.h"
#include "waitset_internal.h"

struct ln_svc_group {
    ln_client* clnt;
    char name[LN_SVC_MAX_NAME + 1];
    int epfd;
    pthread_rwlock_t life; /* shared: handling an event; exclusive: removing endpoints */
    pthread_mutex_t table_lock;
    ln_svc_endpoint** slots;
    uint32_t* gens;
    uint32_t nslots, cap;
    uint32_t* free_slots;
    uint32_t nfree;
    unsigned nproviders;
    ln_svc_pool* pool; /* set once, under the state lock */
    ln_svc_group* next;
};

struct ln_svc_pool {
    ln_client* clnt;
    char name[LN_SVC_MAX_NAME + 1];
    int epfd;   /* the epoll fds of its groups, and the stop eventfd */
    int stopfd; /* eventfd */
    pthread_mutex_t lock;
    pthread_cond_t more; /* max grew, or stop */
    pthread_t threads[LN_SVC_MAX_POOL_THREADS];
    unsigned started, max;
    int stop;
    int ngroups;
    ln_svc_pool* next;
};

struct ln_svc_state {
    pthread_mutex_t lock;
    ln_svc_group* groups;
    ln_svc_pool* pools;
};

/* The group whose event this thread is handling, to refuse re-entrant calls that would
 * deadlock on its lock. */
static _Thread_local ln_svc_group* tls_handling;

static struct ln_svc_state* state_of(ln_client* clnt, int create)
{
    pthread_mutex_lock(&clnt->state_lock);
    struct ln_svc_state* s = clnt->svc;
    if (s == NULL && create) {
        s = calloc(1, sizeof *s);
        if (s != NULL) {
            pthread_mutex_init(&s->lock, NULL);
            clnt->svc = s;
        }
    }
    pthread_mutex_unlock(&clnt->state_lock);
    return s;
}

static const char* shown(const char* group) { return group[0] ? group : "(default)"; }

int ln_svc_group_get(ln_client* clnt, const char* name, int create, ln_svc_group** out)
{
    *out = NULL;
    if (name == NULL)
        name = "";
    if (strlen(name) > LN_SVC_MAX_NAME)
        return ln_set_error(clnt, LN_EINVAL, "service group name is over %d bytes",
                            LN_SVC_MAX_NAME);
    struct ln_svc_state* s = state_of(clnt, create);
    if (s == NULL && create)
        return ln_set_error(clnt, LN_ENOMEM, "out of memory for service group %s", shown(name));
    if (s == NULL)
        return ln_set_error(clnt, LN_ENOTFOUND, "no service is registered in group %s",
                            shown(name));
    int rc = LN_OK;
    pthread_mutex_lock(&s->lock);
    ln_svc_group* g = s->groups;
    while (g != NULL && strcmp(g->name, name) != 0)
        g = g->next;
    if (g == NULL && create) {
        g = calloc(1, sizeof *g);
        int epfd = g ? epoll_create1(EPOLL_CLOEXEC) : -1;
        if (epfd < 0) {
            int err = g ? errno : ENOMEM;
            free(g);
            g = NULL;
            rc = ln_set_errno_error(clnt, err, "cannot create service group %s", shown(name));
        } else {
            g->clnt = clnt;
            snprintf(g->name, sizeof g->name, "%s", name);
            g->epfd = epfd;
            pthread_rwlockattr_t attr;
            pthread_rwlockattr_init(&attr);
            /* Handlers come and go all the time; a provider being removed must not starve. */
            pthread_rwlockattr_setkind_np(&attr, PTHREAD_RWLOCK_PREFER_WRITER_NONRECURSIVE_NP);
            pthread_rwlock_init(&g->life, &attr);
            pthread_rwlockattr_destroy(&attr);
            pthread_mutex_init(&g->table_lock, NULL);
            g->next = s->groups;
            s->groups = g;
        }
    } else if (g == NULL) {
        rc = ln_set_error(clnt, LN_ENOTFOUND, "no service is registered in group %s", shown(name));
    }
    pthread_mutex_unlock(&s->lock);
    *out = g;
    return rc;
}

/* ---- the endpoint table ---- */

static uint64_t key_of(const ln_svc_group* g, uint32_t index)
{
    return (uint64_t)g->gens[index] << 32 | index;
}

/* Puts ep into a slot and into the epoll set, armed.  LN_OK or LN_ENOMEM/LN_ESYS (recorded). */
static int add_endpoint(ln_svc_group* g, ln_svc_endpoint* ep)
{
    pthread_mutex_lock(&g->table_lock);
    uint32_t index;
    if (g->nfree > 0) {
        index = g->free_slots[--g->nfree];
    } else {
        if (g->nslots == g->cap) {
            uint32_t cap = g->cap ? 2 * g->cap : 16;
            ln_svc_endpoint** slots = realloc(g->slots, cap * sizeof *slots);
            if (slots != NULL)
                g->slots = slots;
            uint32_t* gens = slots ? realloc(g->gens, cap * sizeof *gens) : NULL;
            if (gens != NULL)
                g->gens = gens;
            uint32_t* free_slots = gens ? realloc(g->free_slots, cap * sizeof *free_slots) : NULL;
            if (free_slots == NULL) {
                pthread_mutex_unlock(&g->table_lock);
                return ln_set_error(g->clnt, LN_ENOMEM, "out of memory for a service endpoint");
            }
            g->free_slots = free_slots;
            g->cap = cap;
        }
        index = g->nslots++;
        g->gens[index] = 1;
    }
    g->slots[index] = ep;
    ep->index = index;
    struct epoll_event ev = {.events = EPOLLIN | EPOLLONESHOT, .data.u64 = key_of(g, index)};
    int rc = LN_OK;
    if (epoll_ctl(g->epfd, EPOLL_CTL_ADD, ep->fd, &ev) != 0) {
        rc = ln_set_errno_error(g->clnt, errno, "cannot watch a service socket");
        g->slots[index] = NULL;
        g->gens[index]++;
        g->free_slots[g->nfree++] = index;
    }
    pthread_mutex_unlock(&g->table_lock);
    return rc;
}

static void rearm(ln_svc_group* g, ln_svc_endpoint* ep)
{
    pthread_mutex_lock(&g->table_lock);
    struct epoll_event ev = {.events = EPOLLIN | EPOLLONESHOT, .data.u64 = key_of(g, ep->index)};
    epoll_ctl(g->epfd, EPOLL_CTL_MOD, ep->fd, &ev);
    pthread_mutex_unlock(&g->table_lock);
}

/* Takes ep out of the table and the epoll set, closes and frees it. */
static void remove_endpoint(ln_svc_group* g, ln_svc_endpoint* ep)
{
    pthread_mutex_lock(&g->table_lock);
    epoll_ctl(g->epfd, EPOLL_CTL_DEL, ep->fd, NULL);
    g->slots[ep->index] = NULL;
    g->gens[ep->index]++;
    g->free_slots[g->nfree++] = ep->index;
    pthread_mutex_unlock(&g->table_lock);
    ln_svc_endpoint_free(ep);
}

static ln_svc_endpoint* lookup(ln_svc_group* g, uint64_t key)
{
    uint32_t index = (uint32_t)key;
    ln_svc_endpoint* ep = NULL;
    pthread_mutex_lock(&g->table_lock);
    if (index < g->nslots && g->gens[index] == (uint32_t)(key >> 32))
        ep = g->slots[index];
    pthread_mutex_unlock(&g->table_lock);
    return ep;
}

int ln_svc_group_add_listener(ln_svc_group* g, ln_service_provider* prov, int fd, int tcp)
{
    ln_svc_endpoint* ep = calloc(1, sizeof *ep);
    if (ep == NULL)
        return ln_set_error(g->clnt, LN_ENOMEM, "out of memory for a service socket");
    ep->kind = LN_SVC_EP_LISTEN;
    ep->fd = fd;
    ep->prov = prov;
    ep->tcp = tcp;
    int rc = add_endpoint(g, ep);
    if (rc != LN_OK) {
        free(ep);
        return rc;
    }
    pthread_rwlock_wrlock(&g->life);
    g->nproviders++; /* counted once per listener; remove_provider subtracts the same */
    pthread_rwlock_unlock(&g->life);
    return LN_OK;
}

int ln_svc_group_remove_provider(ln_svc_group* g, ln_service_provider* prov)
{
    if (tls_handling == g)
        return ln_set_error(g->clnt, LN_EBUSY,
                            "service \"%s\" cannot be unregistered from a handler of its group",
                            prov->name);
    pthread_rwlock_wrlock(&g->life);
    for (uint32_t i = 0; i < g->nslots; i++) {
        ln_svc_endpoint* ep = g->slots[i];
        if (ep != NULL && ep->prov == prov) {
            if (ep->kind == LN_SVC_EP_LISTEN)
                g->nproviders--;
            remove_endpoint(g, ep);
        }
    }
    pthread_rwlock_unlock(&g->life);
    return LN_OK;
}

/* ---- handling ---- */

static void accept_connections(ln_svc_group* g, ln_svc_endpoint* listener)
{
    for (int i = 0; i < 16; i++) {
        int fd = accept4(listener->fd, NULL, NULL, SOCK_NONBLOCK | SOCK_CLOEXEC);
        if (fd < 0)
            break; /* EAGAIN: done; anything else (EMFILE, ECONNABORTED): try again later */
        ln_svc_endpoint* ep = calloc(1, sizeof *ep);
        if (ep == NULL) {
            close(fd);
            break;
        }
        ep->kind = LN_SVC_EP_CONN;
        ep->fd = fd;
        ep->prov = listener->prov;
        ep->tcp = listener->tcp;
        ln_wbuf_init(&ep->tx);
        ln_arena_init(&ep->arena, 0);
        if (add_endpoint(g, ep) != LN_OK)
            ln_svc_endpoint_free(ep);
    }
}

/* Handles one event of group g: the number of requests answered. */
static int dispatch(ln_svc_group* g, uint64_t key)
{
    pthread_rwlock_rdlock(&g->life);
    ln_svc_group* outer = tls_handling;
    tls_handling = g;
    int answered = 0;
    ln_svc_endpoint* ep = lookup(g, key);
    if (ep != NULL && ep->kind == LN_SVC_EP_LISTEN) {
        accept_connections(g, ep);
        rearm(g, ep);
    } else if (ep != NULL) {
        int n = ln_svc_conn_readable(ep);
        if (n < 0) {
            remove_endpoint(g, ep);
        } else {
            answered = n;
            rearm(g, ep);
        }
    }
    tls_handling = outer;
    pthread_rwlock_unlock(&g->life);
    return answered;
}

/* Reports the call counts of the group's providers that changed (idle time only). */
static void flush_reports(ln_svc_group* g)
{
    pthread_rwlock_rdlock(&g->life);
    for (uint32_t i = 0; i < g->nslots; i++) {
        pthread_mutex_lock(&g->table_lock);
        ln_svc_endpoint* ep = g->slots[i];
        ln_service_provider* prov = ep != NULL && ep->kind == LN_SVC_EP_LISTEN ? ep->prov : NULL;
        pthread_mutex_unlock(&g->table_lock);
        if (prov != NULL)
            ln_svc_report_calls(prov, 1);
    }
    pthread_rwlock_unlock(&g->life);
}

static int remaining_ms(const struct timespec* deadline)
{
    if (deadline == NULL)
        return -1;
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    double left =
        (double)(deadline->tv_sec - now.tv_sec) + (double)(deadline->tv_nsec - now.tv_nsec) * 1e-9;
    if (left <= 0)
        return 0;
    return left > 1e6 ? 1000000000 : (int)ceil(left * 1000.0);
}

/* The existing group `group` of clnt, which no thread pool handles (its thread handles it). */
static int unpooled_group(ln_client* clnt, const char* group, ln_svc_group** out)
{
    int rc = ln_svc_group_get(clnt, group, 0, out);
    if (rc != LN_OK)
        return rc;
    if ((*out)->pool != NULL)
        return ln_set_error(clnt, LN_EBUSY, "service group %s is handled by thread pool \"%s\"",
                            shown((*out)->name), (*out)->pool->name);
    return LN_OK;
}

int ln_wait_and_handle_service_group_requests(ln_client* clnt, const char* group, double timeout)
{
    int rc = ln_client_check(clnt);
    if (rc != LN_OK)
        return rc;
    if (isnan(timeout))
        return ln_set_error(clnt, LN_EINVAL,
                            "wait_and_handle_service_group_requests: timeout is NaN");
    ln_svc_group* g;
    if ((rc = unpooled_group(clnt, group, &g)) != LN_OK)
        return rc;
    if (tls_handling != NULL)
        return ln_set_error(clnt, LN_EBUSY,
                            "wait_and_handle_service_group_requests called from a handler");
    struct timespec ts;
    const struct timespec* deadline = isinf(timeout) ? NULL : ln_net_deadline(&ts, timeout);
    int handled = 0;
    for (;;) {
        struct epoll_event ev[16];
        int wait = handled > 0 ? 0 : remaining_ms(deadline);
        int n = epoll_wait(g->epfd, ev, 16, wait);
        if (n < 0) {
            if (errno != EINTR)
                return ln_set_errno_error(clnt, errno, "cannot wait for service requests");
            if (handled > 0)
                return handled;
            return ln_set_error(clnt, LN_EINTR, "interrupted while waiting for service requests");
        }
        for (int i = 0; i < n; i++)
            handled += dispatch(g, ev[i].data.u64);
        if (n == 0 && (handled > 0 || wait == 0)) {
            if (handled == 0)
                flush_reports(g);
            return handled;
        }
    }
}

/* ---- thread pools ---- */

static void* pool_thread(void* arg);

struct pool_thread_arg {
    ln_svc_pool* pool;
    unsigned index;
};

/* Starts threads up to pool->max; pool->lock held. */
static int start_threads(ln_svc_pool* p)
{
    while (p->started < p->max && p->ngroups > 0) {
        struct pool_thread_arg* a = malloc(sizeof *a);
        if (a == NULL)
            return ln_set_error(p->clnt, LN_ENOMEM, "out of memory for a pool thread");
        a->pool = p;
        a->index = p->started;
        int err = pthread_create(&p->threads[p->started], NULL, pool_thread, a);
        if (err != 0) {
            free(a);
            return ln_set_errno_error(p->clnt, err, "cannot start a thread of pool \"%s\"",
                                      p->name);
        }
        p->started++;
    }
    return LN_OK;
}

static void flush_idle_reports(ln_svc_pool* p)
{
    struct ln_svc_state* s = p->clnt->svc;
    pthread_mutex_lock(&s->lock);
    ln_svc_group* groups[64];
    int n = 0;
    for (ln_svc_group* g = s->groups; g != NULL && n < 64; g = g->next)
        if (g->pool == p)
            groups[n++] = g;
    pthread_mutex_unlock(&s->lock);
    for (int i = 0; i < n; i++)
        flush_reports(groups[i]);
}

static void* pool_thread(void* arg)
{
    struct pool_thread_arg a = *(struct pool_thread_arg*)arg;
    free(arg);
    ln_svc_pool* p = a.pool;
    for (;;) {
        pthread_mutex_lock(&p->lock);
        while (!p->stop && a.index >= p->max)
            pthread_cond_wait(&p->more, &p->lock);
        int stop = p->stop;
        pthread_mutex_unlock(&p->lock);
        if (stop)
            return NULL;
        struct epoll_event ev;
        int n = epoll_wait(p->epfd, &ev, 1, 1000);
        if (n == 0) {
            flush_idle_reports(p);
            continue;
        }
        if (n != 1 || ev.data.ptr == NULL)
            continue; /* EINTR, or the stop eventfd: re-check the flags */
        ln_svc_group* g = ev.data.ptr;
        struct epoll_event gev;
        if (epoll_wait(g->epfd, &gev, 1, 0) == 1)
            dispatch(g, gev.data.u64);
    }
}

static int pool_get(ln_client* clnt, const char* name, ln_svc_pool** out)
{
    *out = NULL;
    if (name == NULL)
        name = "";
    if (strlen(name) > LN_SVC_MAX_NAME)
        return ln_set_error(clnt, LN_EINVAL, "thread pool name is over %d bytes", LN_SVC_MAX_NAME);
    struct ln_svc_state* s = state_of(clnt, 1);
    if (s == NULL)
        return ln_set_error(clnt, LN_ENOMEM, "out of memory for thread pool \"%s\"", name);
    int rc = LN_OK;
    pthread_mutex_lock(&s->lock);
    ln_svc_pool* p = s->pools;
    while (p != NULL && strcmp(p->name, name) != 0)
        p = p->next;
    if (p == NULL) {
        p = calloc(1, sizeof *p);
        int epfd = p ? epoll_create1(EPOLL_CLOEXEC) : -1;
        int stopfd = epfd >= 0 ? eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK) : -1;
        struct epoll_event ev = {.events = EPOLLIN, .data.ptr = NULL};
        if (stopfd < 0 || epoll_ctl(epfd, EPOLL_CTL_ADD, stopfd, &ev) != 0) {
            int err = p ? errno : ENOMEM;
            if (epfd >= 0)
                close(epfd);
            if (stopfd >= 0)
                close(stopfd);
            free(p);
            p = NULL;
            rc = ln_set_errno_error(clnt, err, "cannot create thread pool \"%s\"", name);
        } else {
            p->clnt = clnt;
            snprintf(p->name, sizeof p->name, "%s", name);
            p->epfd = epfd;
            p->stopfd = stopfd;
            p->max = 1;
            pthread_mutex_init(&p->lock, NULL);
            pthread_cond_init(&p->more, NULL);
            p->next = s->pools;
            s->pools = p;
        }
    }
    pthread_mutex_unlock(&s->lock);
    *out = p;
    return rc;
}

int ln_set_max_threads(ln_client* clnt, const char* pool, unsigned max_threads)
{
    int rc = ln_client_check(clnt);
    if (rc != LN_OK)
        return rc;
    if (max_threads < 1 || max_threads > LN_SVC_MAX_POOL_THREADS)
        return ln_set_error(clnt, LN_EINVAL, "max_threads %u is not in 1..%d", max_threads,
                            LN_SVC_MAX_POOL_THREADS);
    ln_svc_pool* p;
    rc = pool_get(clnt, pool, &p);
    if (rc != LN_OK)
        return rc;
    pthread_mutex_lock(&p->lock);
    p->max = max_threads;
    rc = start_threads(p);
    pthread_cond_broadcast(&p->more);
    pthread_mutex_unlock(&p->lock);
    return rc;
}

int ln_handle_service_group_in_thread_pool(ln_client* clnt, const char* group, const char* pool)
{
    int rc = ln_client_check(clnt);
    if (rc != LN_OK)
        return rc;
    ln_svc_group* g;
    ln_svc_pool* p;
    rc = ln_svc_group_get(clnt, group, 1, &g);
    if (rc == LN_OK)
        rc = pool_get(clnt, pool, &p);
    if (rc != LN_OK)
        return rc;
    struct ln_svc_state* s = state_of(clnt, 0);
    pthread_mutex_lock(&s->lock);
    if (g->pool != NULL) {
        int same = g->pool == p;
        pthread_mutex_unlock(&s->lock);
        return same ? LN_OK
                    : ln_set_error(clnt, LN_EBUSY,
                                   "service group %s is already handled by thread pool \"%s\"",
                                   shown(g->name), g->pool->name);
    }
    struct epoll_event ev = {.events = EPOLLIN, .data.ptr = g};
    if (epoll_ctl(p->epfd, EPOLL_CTL_ADD, g->epfd, &ev) != 0) {
        pthread_mutex_unlock(&s->lock);
        return ln_set_errno_error(clnt, errno, "cannot add service group %s to thread pool",
                                  shown(g->name));
    }
    g->pool = p;
    pthread_mutex_unlock(&s->lock);
    pthread_mutex_lock(&p->lock);
    p->ngroups++;
    rc = start_threads(p);
    pthread_mutex_unlock(&p->lock);
    return rc;
}

void ln_svc_client_stop_pools(ln_client* clnt)
{
    struct ln_svc_state* s = state_of(clnt, 0);
    if (s == NULL)
        return;
    for (ln_svc_pool* p = s->pools; p != NULL; p = p->next) {
        pthread_mutex_lock(&p->lock);
        p->stop = 1;
        pthread_cond_broadcast(&p->more);
        pthread_mutex_unlock(&p->lock);
        uint64_t one = 1;
        if (write(p->stopfd, &one, sizeof one) < 0) {
            /* the counter cannot overflow with one write per pool; threads also time out */
        }
        for (unsigned i = 0; i < p->started; i++)
            pthread_join(p->threads[i], NULL);
        p->started = 0;
    }
}

void ln_svc_client_free(ln_client* clnt)
{
    struct ln_svc_state* s = clnt->svc;
    if (s == NULL)
        return;
    ln_svc_client_stop_pools(clnt);
    while (s->pools != NULL) {
        ln_svc_pool* p = s->pools;
        s->pools = p->next;
        close(p->epfd);
        close(p->stopfd);
        pthread_mutex_destroy(&p->lock);
        pthread_cond_destroy(&p->more);
        free(p);
    }
    while (s->groups != NULL) {
        ln_svc_group* g = s->groups;
        s->groups = g->next;
        for (uint32_t i = 0; i < g->nslots; i++)
            if (g->slots[i] != NULL)
                ln_svc_endpoint_free(g->slots[i]);
        close(g->epfd);
        pthread_rwlock_destroy(&g->life);
        pthread_mutex_destroy(&g->table_lock);
        free(g->slots);
        free(g->gens);
        free(g->free_slots);
        free(g);
    }
    pthread_mutex_destroy(&s->lock);
    free(s);
    clnt->svc = NULL;
}

/* ---- waitsets (waitset_internal.h) ---- */

int ln_svc_group_wait_fd(ln_client* clnt, const char* group, int* fd)
{
    int rc = ln_client_check(clnt);
    if (rc != LN_OK)
        return rc;
    ln_svc_group* g;
    if ((rc = unpooled_group(clnt, group, &g)) != LN_OK)
        return rc;
    *fd = g->epfd;
    return LN_OK;
}
