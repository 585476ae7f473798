/* waitset.c — ln_waitset (ln.h, "the waitset"; docs/waiting.md): one epoll set holding the
 * waitset's bell (bell.h: an abstract datagram socket that publishers, the manager and libln's
 * own threads ring with an attachment's id), attached file descriptors and service groups'
 * epoll sets.  A wait looks at what rang, at inports it reported data for last time (data is
 * level-triggered), at timers and deadlines that fell due, and sleeps in epoll_pwait2 until
 * the nearest of them otherwise (in recvmmsg on the bell when nothing else is to be watched
 * and nothing is timed).
 *
 * Attachments live in a table; an id is (generation << 16) | (index + 1), so a late bell for
 * an attachment that was detached and whose slot was reused is recognised and dropped.
 * Everything is under `mu`, which the waiter gives up only while it sleeps; attaching from
 * another thread rings the bell so that the waiter takes the change into account.
 * Waiting allocates nothing: the table grows in attach. */
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/random.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "bell.h"
#include "client_internal.h"
#include "waitset_internal.h"

#define LN_WAITSET_MAGIC 0x4c4e5753u
#define NONE (-1)
#define BELL_KEY UINT64_MAX /* epoll data of the bell socket */
#define DRAIN_BATCH 64

enum att_kind { ATT_FREE, ATT_INPORT, ATT_GROUP, ATT_PARAMS, ATT_FD, ATT_TIMER };
enum { RECHECK, TIMED, LISTS }; /* the unordered lists of attachments (push, unlink_from) */

/* fired bits: one per kind of event */
#define FIRE(kind) (1u << (kind))

typedef struct att {
    uint8_t kind;
    uint16_t gen;
    void* user_data;
    /* inports */
    ln_inport* port;
    uint32_t flags;
    int alive;         /* the topic had a publisher when last looked at */
    uint64_t last_seq; /* write_seq when last looked at */
    int64_t deadline;  /* ns, 0: none */
    int64_t last_ns;   /* CLOCK_MONOTONIC of the last sample or deadline report */
    ln_parameter_block* blk;
    int fd;          /* ATT_FD, ATT_GROUP */
    int64_t next_ns; /* timers: next expiry */
    int64_t period;  /* ns, 0: once */
    /* what fired and is not reported yet */
    uint32_t fired;
    uint32_t fd_events, timer_count, deadline_count;
    int next_fired;
    int in_fired;
    int next[LISTS]; /* in the lists below */
    int in[LISTS];
} att;

struct ln_waitset {
    uint32_t magic;
    pthread_mutex_t mu;
    int epfd;
    int sock;
    uint64_t bell;
    uint32_t qlen; /* datagrams the bell holds before senders get EAGAIN */
    att* a;
    uint32_t cap, used;
    uint32_t polled; /* attached descriptors and service groups (in the epoll set) */
    int free_head;   /* free slots chained through next_fired */
    int fired_head, fired_tail;
    int head[LISTS];
    _Atomic uint32_t triggers;
    _Atomic int waiting;
};

static int64_t now_ns(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (int64_t)t.tv_sec * 1000000000LL + t.tv_nsec;
}

static int ws_check(const ln_waitset* ws, const char* what)
{
    if (ws == NULL || ws->magic != LN_WAITSET_MAGIC)
        return ln_set_error(NULL, LN_EBADHANDLE, "%s: invalid waitset handle", what);
    return LN_OK;
}

static uint32_t id_of(const ln_waitset* ws, int i)
{
    return ((uint32_t)ws->a[i].gen << 16) | (uint32_t)(i + 1);
}

/* The slot of attachment id, or NONE if it is not (any more) attached. */
static int slot_of(const ln_waitset* ws, uint32_t id)
{
    uint32_t low = id & 0xffffu;
    if (low == 0 || low > ws->cap)
        return NONE;
    int i = (int)low - 1;
    if (ws->a[i].kind == ATT_FREE || ws->a[i].gen != (uint16_t)(id >> 16))
        return NONE;
    return i;
}

static uint32_t read_qlen(void)
{
    uint32_t q = 10;
    FILE* f = fopen("/proc/sys/net/unix/max_dgram_qlen", "re");
    if (f != NULL) {
        unsigned v;
        if (fscanf(f, "%u", &v) == 1 && v > 0)
            q = v;
        fclose(f);
    }
    return q;
}

/* A bound bell socket with a fresh random id. */
static int open_bell(ln_waitset* ws)
{
    /* blocking: a wait with only the bell to watch sleeps in recvmmsg itself (every other
     * receive passes MSG_DONTWAIT) */
    ws->sock = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (ws->sock < 0)
        return ln_set_errno_error(NULL, errno, "ln_waitset_create: socket");
    for (int tries = 0; tries < 8; tries++) {
        uint64_t id = 0;
        if (getrandom(&id, sizeof id, 0) != (ssize_t)sizeof id)
            return ln_set_errno_error(NULL, errno, "ln_waitset_create: getrandom");
        if (id == 0)
            continue;
        struct sockaddr_un addr;
        socklen_t len = ln_bell_address(id, &addr);
        if (bind(ws->sock, (struct sockaddr*)&addr, len) == 0) {
            ws->bell = id;
            return LN_OK;
        }
        if (errno != EADDRINUSE)
            break;
    }
    return ln_set_errno_error(NULL, errno, "ln_waitset_create: cannot bind its bell socket");
}

int ln_waitset_create(ln_waitset** out)
{
    if (out == NULL)
        return ln_set_error(NULL, LN_EINVAL, "ln_waitset_create: out is NULL");
    *out = NULL;
    ln_waitset* ws = calloc(1, sizeof *ws);
    if (ws == NULL)
        return ln_set_error(NULL, LN_ENOMEM, "ln_waitset_create: out of memory");
    ws->sock = -1;
    ws->free_head = ws->fired_head = ws->fired_tail = NONE;
    ws->head[RECHECK] = ws->head[TIMED] = NONE;
    ws->qlen = read_qlen();
    int rc = LN_OK;
    ws->epfd = epoll_create1(EPOLL_CLOEXEC);
    if (ws->epfd < 0)
        rc = ln_set_errno_error(NULL, errno, "ln_waitset_create: epoll_create1");
    if (rc == LN_OK)
        rc = open_bell(ws);
    if (rc == LN_OK) {
        struct epoll_event ev = {.events = EPOLLIN, .data.u64 = BELL_KEY};
        if (epoll_ctl(ws->epfd, EPOLL_CTL_ADD, ws->sock, &ev) != 0)
            rc = ln_set_errno_error(NULL, errno, "ln_waitset_create: epoll_ctl");
    }
    if (rc != LN_OK) {
        if (ws->sock >= 0)
            close(ws->sock);
        if (ws->epfd >= 0)
            close(ws->epfd);
        free(ws);
        return rc;
    }
    pthread_mutex_init(&ws->mu, NULL);
    ws->magic = LN_WAITSET_MAGIC;
    *out = ws;
    return LN_OK;
}

/* ---- the lists (singly linked through the table; indices, never pointers) ---- */

static void push_fired(ln_waitset* ws, int i, uint32_t bits)
{
    att* t = &ws->a[i];
    t->fired |= bits;
    if (t->in_fired)
        return;
    t->in_fired = 1;
    t->next_fired = NONE;
    if (ws->fired_tail == NONE)
        ws->fired_head = i;
    else
        ws->a[ws->fired_tail].next_fired = i;
    ws->fired_tail = i;
}

static int pop_fired(ln_waitset* ws)
{
    int i = ws->fired_head;
    if (i == NONE)
        return NONE;
    ws->fired_head = ws->a[i].next_fired;
    if (ws->fired_head == NONE)
        ws->fired_tail = NONE;
    ws->a[i].in_fired = 0;
    return i;
}

static void unlink_fired(ln_waitset* ws, int i)
{
    int prev = NONE;
    for (int k = ws->fired_head; k != NONE; prev = k, k = ws->a[k].next_fired) {
        if (k != i)
            continue;
        if (prev == NONE)
            ws->fired_head = ws->a[k].next_fired;
        else
            ws->a[prev].next_fired = ws->a[k].next_fired;
        if (ws->fired_tail == i)
            ws->fired_tail = prev;
        break;
    }
    ws->a[i].in_fired = 0;
}

/* The other lists: RECHECK (looked at by the next wait: inports reported with data last time,
 * new attachments) and TIMED (timers, inports with a deadline); order does not matter. */
static void push(ln_waitset* ws, int list, int i)
{
    if (ws->a[i].in[list])
        return;
    ws->a[i].in[list] = 1;
    ws->a[i].next[list] = ws->head[list];
    ws->head[list] = i;
}

static void unlink_from(ln_waitset* ws, int list, int i)
{
    int* link = &ws->head[list];
    while (*link != NONE && *link != i)
        link = &ws->a[*link].next[list];
    if (*link == i)
        *link = ws->a[i].next[list];
    ws->a[i].in[list] = 0;
}

/* ---- attaching ---- */

/* A free slot (growing the table), filled with kind and user_data; NONE with the error set. */
static int new_slot(ln_waitset* ws, uint8_t kind, void* user_data, int* rc)
{
    if (ws->free_head == NONE) {
        if (ws->cap >= LN_WAITSET_MAX_ATTACHMENTS) {
            *rc = ln_set_error(NULL, LN_ELIMIT, "a waitset holds at most %d attachments",
                               LN_WAITSET_MAX_ATTACHMENTS);
            return NONE;
        }
        uint32_t cap = ws->cap ? ws->cap * 2 : 16;
        if (cap > LN_WAITSET_MAX_ATTACHMENTS)
            cap = LN_WAITSET_MAX_ATTACHMENTS;
        att* grown = realloc(ws->a, cap * sizeof *grown);
        if (grown == NULL) {
            *rc = ln_set_error(NULL, LN_ENOMEM, "waitset: out of memory for attachments");
            return NONE;
        }
        memset(grown + ws->cap, 0, (cap - ws->cap) * sizeof *grown);
        for (uint32_t k = cap; k-- > ws->cap;) {
            grown[k].next_fired = ws->free_head;
            ws->free_head = (int)k;
        }
        ws->a = grown;
        ws->cap = cap;
    }
    int i = ws->free_head;
    att* t = &ws->a[i];
    ws->free_head = t->next_fired;
    uint16_t gen = (uint16_t)(t->gen + 1 ? t->gen + 1 : 1);
    memset(t, 0, sizeof *t);
    t->gen = gen;
    t->kind = kind;
    t->user_data = user_data;
    t->fd = -1;
    t->next_fired = t->next[RECHECK] = t->next[TIMED] = NONE;
    ws->used++;
    return i;
}

static void free_slot(ln_waitset* ws, int i)
{
    att* t = &ws->a[i];
    if (t->in_fired)
        unlink_fired(ws, i);
    for (int list = 0; list < LISTS; list++)
        if (t->in[list])
            unlink_from(ws, list, i);
    t->kind = ATT_FREE;
    t->next_fired = ws->free_head;
    ws->free_head = i;
    ws->used--;
}

/* Undo what attaching did outside the table. */
static void release(ln_waitset* ws, int i)
{
    att* t = &ws->a[i];
    switch (t->kind) {
    case ATT_INPORT:
        ln_inport_bell(t->port, NULL, 0, 0);
        break;
    case ATT_PARAMS:
        ln_param_bell(t->blk, NULL, 0, 0);
        break;
    case ATT_FD:
    case ATT_GROUP:
        epoll_ctl(ws->epfd, EPOLL_CTL_DEL, t->fd, NULL); /* fails if closed already: fine */
        ws->polled--;
        break;
    default:
        break;
    }
    free_slot(ws, i);
}

/* Start of every attach: the handle and a lock; ends with finish(). */
static int begin(ln_waitset* ws, const char* what)
{
    int rc = ws_check(ws, what);
    if (rc == LN_OK)
        pthread_mutex_lock(&ws->mu);
    return rc;
}

/* Unlocks, gives the id, and wakes a waiter so that it looks at the new attachment. */
static int finish(ln_waitset* ws, int i, int rc, uint32_t* id)
{
    if (rc == LN_OK && id != NULL)
        *id = id_of(ws, i);
    if (rc == LN_OK)
        push(ws, RECHECK, i); /* looked at by the next wait, ready or not */
    pthread_mutex_unlock(&ws->mu);
    if (rc == LN_OK && atomic_load_explicit(&ws->waiting, memory_order_seq_cst))
        ln_bell_ring(ws->bell, 0);
    return rc;
}

static int64_t seconds_ns(double s) { return (int64_t)llround(s * 1e9); }

static int bad_seconds(double s) { return isnan(s) || s < 0 || s > 1e9; }

int ln_waitset_attach_inport(ln_waitset* ws, ln_inport* port, uint32_t flags, double deadline,
                             void* user_data, uint32_t* id)
{
    int rc = begin(ws, "ln_waitset_attach_inport");
    if (rc != LN_OK)
        return rc;
    int i = NONE;
    if ((rc = ln_inport_check(port, "ln_waitset_attach_inport")) != LN_OK)
        goto out;
    if (flags & ~(LN_WAIT_ON_DATA | LN_WAIT_ON_LIVELINESS) || bad_seconds(deadline)) {
        rc = ln_set_error(NULL, LN_EINVAL,
                          "ln_waitset_attach_inport: flags 0x%x or deadline %g s out of range",
                          flags, deadline);
        goto out;
    }
    if (ln_inport_waitset(port) != NULL) {
        rc = ln_set_error(NULL, LN_EBUSY,
                          "ln_waitset_attach_inport: the inport is attached "
                          "to a waitset already");
        goto out;
    }
    if ((i = new_slot(ws, ATT_INPORT, user_data, &rc)) == NONE)
        goto out;
    att* t = &ws->a[i];
    t->port = port;
    t->flags = flags ? flags : LN_WAIT_ON_DATA;
    t->deadline = seconds_ns(deadline);
    t->last_ns = now_ns();
    t->last_seq = ln_inport_write_seq(port);
    int pubs = ln_inport_live_publishers(port);
    t->alive = pubs > 0;
    if ((rc = ln_inport_bell(port, ws, id_of(ws, i), ws->bell)) != LN_OK) {
        free_slot(ws, i);
        goto out;
    }
    if (t->deadline > 0)
        push(ws, TIMED, i);
out:
    return finish(ws, i, rc, id);
}

int ln_waitset_set_deadline(ln_waitset* ws, uint32_t id, double deadline)
{
    int rc = begin(ws, "ln_waitset_set_deadline");
    if (rc != LN_OK)
        return rc;
    int i = slot_of(ws, id);
    if (i == NONE || ws->a[i].kind != ATT_INPORT)
        rc = ln_set_error(NULL, LN_ENOTFOUND, "ln_waitset_set_deadline: no inport attachment %u",
                          id);
    else if (bad_seconds(deadline))
        rc = ln_set_error(NULL, LN_EINVAL, "ln_waitset_set_deadline: deadline %g s out of range",
                          deadline);
    else {
        att* t = &ws->a[i];
        t->deadline = seconds_ns(deadline);
        t->last_ns = now_ns();
        t->deadline_count = 0;
        t->fired &= ~FIRE(LN_WAIT_DEADLINE);
        if (t->deadline > 0)
            push(ws, TIMED, i);
        else if (t->in[TIMED])
            unlink_from(ws, TIMED, i);
    }
    return finish(ws, i, rc, NULL);
}

/* An fd (a caller's or a service group's epoll set) into the epoll set under the slot's id. */
static int add_fd(ln_waitset* ws, int i, int fd, uint32_t want)
{
    struct epoll_event ev = {.events = (want & LN_WAIT_READABLE ? EPOLLIN : 0u) |
                                       (want & LN_WAIT_WRITABLE ? EPOLLOUT : 0u),
                             .data.u64 = id_of(ws, i)};
    if (epoll_ctl(ws->epfd, EPOLL_CTL_ADD, fd, &ev) != 0)
        return ln_set_errno_error(NULL, errno, "waitset: cannot wait on file descriptor %d", fd);
    ws->a[i].fd = fd;
    ws->polled++;
    return LN_OK;
}

int ln_waitset_attach_service_group(ln_waitset* ws, ln_client* clnt, const char* group,
                                    void* user_data, uint32_t* id)
{
    int fd = -1;
    int rc = ln_svc_group_wait_fd(clnt, group, &fd);
    if (rc != LN_OK)
        return rc;
    if ((rc = begin(ws, "ln_waitset_attach_service_group")) != LN_OK)
        return rc;
    int i = new_slot(ws, ATT_GROUP, user_data, &rc);
    if (i != NONE && (rc = add_fd(ws, i, fd, LN_WAIT_READABLE)) != LN_OK) {
        free_slot(ws, i);
        i = NONE;
    }
    return finish(ws, i, rc, id);
}

int ln_waitset_attach_provider(ln_waitset* ws, ln_service_provider* provider, void* user_data,
                               uint32_t* id)
{
    ln_client* clnt;
    const char* group;
    int rc = ln_provider_group_of(provider, &clnt, &group);
    return rc != LN_OK ? rc : ln_waitset_attach_service_group(ws, clnt, group, user_data, id);
}

int ln_waitset_attach_event_handler(ln_waitset* ws, ln_event_handler* handler, void* user_data,
                                    uint32_t* id)
{
    ln_service_provider* prov;
    int rc = ln_event_handler_provider(handler, &prov);
    return rc != LN_OK ? rc : ln_waitset_attach_provider(ws, prov, user_data, id);
}

int ln_waitset_attach_parameter_block(ln_waitset* ws, ln_parameter_block* blk, void* user_data,
                                      uint32_t* id)
{
    int rc = ln_param_check_handle(blk, "ln_waitset_attach_parameter_block");
    if (rc != LN_OK)
        return rc;
    if ((rc = begin(ws, "ln_waitset_attach_parameter_block")) != LN_OK)
        return rc;
    int i = new_slot(ws, ATT_PARAMS, user_data, &rc);
    if (i != NONE) {
        ws->a[i].blk = blk;
        if ((rc = ln_param_bell(blk, ws, id_of(ws, i), ws->bell)) != LN_OK) {
            free_slot(ws, i);
            i = NONE;
        }
    }
    return finish(ws, i, rc, id);
}

int ln_waitset_attach_fd(ln_waitset* ws, int fd, uint32_t events, void* user_data, uint32_t* id)
{
    int rc = begin(ws, "ln_waitset_attach_fd");
    if (rc != LN_OK)
        return rc;
    int i = NONE;
    if (fd < 0 || events == 0 || (events & ~(LN_WAIT_READABLE | LN_WAIT_WRITABLE)))
        rc = ln_set_error(NULL, LN_EINVAL, "ln_waitset_attach_fd: fd %d or events 0x%x invalid", fd,
                          events);
    else if ((i = new_slot(ws, ATT_FD, user_data, &rc)) != NONE &&
             (rc = add_fd(ws, i, fd, events)) != LN_OK) {
        free_slot(ws, i);
        i = NONE;
    }
    return finish(ws, i, rc, id);
}

int ln_waitset_attach_timer(ln_waitset* ws, int64_t first_ns, double period, void* user_data,
                            uint32_t* id)
{
    int rc = begin(ws, "ln_waitset_attach_timer");
    if (rc != LN_OK)
        return rc;
    int i = NONE;
    if (bad_seconds(period) || first_ns < 0 || (first_ns == 0 && period == 0))
        rc = ln_set_error(NULL, LN_EINVAL,
                          "ln_waitset_attach_timer: first %lld ns, period %g s out of range",
                          (long long)first_ns, period);
    else if ((i = new_slot(ws, ATT_TIMER, user_data, &rc)) != NONE) {
        att* t = &ws->a[i];
        t->period = seconds_ns(period);
        t->next_ns = first_ns ? first_ns : now_ns() + t->period;
        push(ws, TIMED, i);
    }
    return finish(ws, i, rc, id);
}

int ln_waitset_detach(ln_waitset* ws, uint32_t id)
{
    int rc = begin(ws, "ln_waitset_detach");
    if (rc != LN_OK)
        return rc;
    int i = slot_of(ws, id);
    if (i == NONE)
        rc = ln_set_error(NULL, LN_ENOTFOUND, "ln_waitset_detach: no attachment %u", id);
    else
        release(ws, i);
    pthread_mutex_unlock(&ws->mu);
    return rc;
}

void ln_waitset_forget(ln_waitset* ws, uint32_t id, const void* object)
{
    if (ws == NULL || ws->magic != LN_WAITSET_MAGIC)
        return;
    pthread_mutex_lock(&ws->mu);
    int i = slot_of(ws, id);
    if (i != NONE && (ws->a[i].port == object || ws->a[i].blk == object))
        release(ws, i);
    pthread_mutex_unlock(&ws->mu);
}

int ln_waitset_destroy(ln_waitset* ws)
{
    int rc = ws_check(ws, "ln_waitset_destroy");
    if (rc != LN_OK)
        return rc;
    if (atomic_load_explicit(&ws->waiting, memory_order_seq_cst))
        return ln_set_error(NULL, LN_EBUSY, "ln_waitset_destroy: a thread waits in it");
    pthread_mutex_lock(&ws->mu);
    for (uint32_t k = 0; k < ws->cap; k++)
        if (ws->a[k].kind != ATT_FREE)
            release(ws, (int)k);
    ws->magic = 0;
    pthread_mutex_unlock(&ws->mu);
    close(ws->sock);
    close(ws->epfd);
    pthread_mutex_destroy(&ws->mu);
    free(ws->a);
    free(ws);
    return LN_OK;
}

/* ---- looking ---- */

/* Looks at an inport: new samples (deadline), readiness, liveliness. */
static void look_inport(ln_waitset* ws, int i, int64_t now)
{
    att* t = &ws->a[i];
    int ready = ln_inport_ready(t->port);
    uint64_t seq = ln_inport_write_seq(t->port);
    if (seq != t->last_seq) {
        t->last_seq = seq;
        t->last_ns = now;
    }
    if ((t->flags & LN_WAIT_ON_DATA) && ready > 0)
        push_fired(ws, i, FIRE(LN_WAIT_DATA));
    int alive = ln_inport_live_publishers(t->port) > 0;
    if (alive != t->alive) {
        t->alive = alive;
        if (t->flags & LN_WAIT_ON_LIVELINESS) {
            /* a quick gone-and-back (or back-and-gone) that was never reported cancels out */
            uint32_t other = FIRE(alive ? LN_WAIT_GONE : LN_WAIT_BACK);
            if (t->fired & other)
                t->fired &= ~other;
            else
                push_fired(ws, i, FIRE(alive ? LN_WAIT_BACK : LN_WAIT_GONE));
        }
    }
}

static void look(ln_waitset* ws, int i, int64_t now)
{
    att* t = &ws->a[i];
    if (t->kind == ATT_INPORT)
        look_inport(ws, i, now);
    else if (t->kind == ATT_PARAMS && ln_param_pending(t->blk))
        push_fired(ws, i, FIRE(LN_WAIT_PARAMETERS));
}

/* When a timer or an inport's deadline falls due next, and its period. */
static int64_t due_of(const att* t)
{
    return t->kind == ATT_TIMER ? t->next_ns : t->last_ns + t->deadline;
}

static int64_t step_of(const att* t) { return t->kind == ATT_TIMER ? t->period : t->deadline; }

/* Timers and deadlines that fell due by `now`; the earliest one still ahead into *next.  A
 * one-shot timer leaves the list once it fired. */
static void look_timed(ln_waitset* ws, int64_t now, int64_t* next)
{
    for (int i = ws->head[TIMED], following; i != NONE; i = following) {
        att* t = &ws->a[i];
        following = t->next[TIMED];
        int64_t due = due_of(t), step = step_of(t);
        if (now >= due) {
            uint64_t times = step > 0 ? 1 + (uint64_t)((now - due) / step) : 1;
            if (t->kind == ATT_TIMER) {
                t->timer_count += (uint32_t)times;
                t->next_ns = due + (int64_t)times * step;
                push_fired(ws, i, FIRE(LN_WAIT_TIMER));
                if (step == 0) {
                    unlink_from(ws, TIMED, i);
                    continue;
                }
            } else {
                t->deadline_count += (uint32_t)times;
                t->last_ns = due + (int64_t)(times - 1) * step;
                push_fired(ws, i, FIRE(LN_WAIT_DEADLINE));
            }
        }
        if (due_of(t) < *next)
            *next = due_of(t);
    }
}

/* Datagrams of the bell, received in one call. */
typedef struct bell_batch {
    uint32_t tags[DRAIN_BATCH];
    struct iovec iov[DRAIN_BATCH];
    struct mmsghdr msgs[DRAIN_BATCH];
} bell_batch;

static int bell_receive(ln_waitset* ws, bell_batch* b, int flags)
{
    for (int k = 0; k < DRAIN_BATCH; k++) {
        b->iov[k] = (struct iovec){.iov_base = &b->tags[k], .iov_len = sizeof b->tags[k]};
        b->msgs[k] = (struct mmsghdr){.msg_hdr = {.msg_iov = &b->iov[k], .msg_iovlen = 1}};
    }
    return recvmmsg(ws->sock, b->msgs, DRAIN_BATCH, flags, NULL);
}

/* Looks at the attachments n received datagrams name, then at what else the bell holds
 * (nothing more to receive when fewer than a batch came: one system call saved, and what
 * comes meanwhile keeps the socket readable).  A bell that may have been full makes it look
 * at every inport and parameter block: a sender that found it full dropped its datagram. */
static void bell_take(ln_waitset* ws, bell_batch* b, int n, int64_t now)
{
    uint32_t total = 0;
    while (n > 0) {
        total += (uint32_t)n;
        for (int k = 0; k < n; k++) {
            if (b->msgs[k].msg_len != sizeof(uint32_t) || b->tags[k] == 0)
                continue; /* a trigger or an attach: looked at by the caller */
            int i = slot_of(ws, b->tags[k]);
            if (i != NONE)
                look(ws, i, now);
        }
        if (n < DRAIN_BATCH)
            break;
        n = bell_receive(ws, b, MSG_DONTWAIT);
    }
    if (total >= ws->qlen)
        for (uint32_t k = 0; k < ws->cap; k++)
            if (ws->a[k].kind == ATT_INPORT || ws->a[k].kind == ATT_PARAMS)
                look(ws, (int)k, now);
}

static void drain_bell(ln_waitset* ws, int64_t now)
{
    bell_batch b;
    bell_take(ws, &b, bell_receive(ws, &b, MSG_DONTWAIT), now);
}

static void on_epoll(ln_waitset* ws, const struct epoll_event* ev, int64_t now)
{
    if (ev->data.u64 == BELL_KEY) {
        drain_bell(ws, now);
        return;
    }
    int i = slot_of(ws, (uint32_t)ev->data.u64);
    if (i == NONE)
        return;
    att* t = &ws->a[i];
    if (t->kind == ATT_GROUP) {
        push_fired(ws, i, FIRE(LN_WAIT_REQUESTS));
    } else if (t->kind == ATT_FD) {
        t->fd_events |= (ev->events & EPOLLIN ? LN_WAIT_READABLE : 0u) |
                        (ev->events & EPOLLOUT ? LN_WAIT_WRITABLE : 0u) |
                        (ev->events & (EPOLLERR | EPOLLHUP) ? LN_WAIT_ERROR : 0u);
        push_fired(ws, i, FIRE(LN_WAIT_FD));
    }
}

/* What is ready without sleeping: the re-checks, triggers, timers; *next the earliest due. */
static void collect(ln_waitset* ws, int64_t now, int64_t* next)
{
    int i = ws->head[RECHECK];
    ws->head[RECHECK] = NONE;
    while (i != NONE) {
        int following = ws->a[i].next[RECHECK];
        ws->a[i].in[RECHECK] = 0;
        att* t = &ws->a[i];
        if (t->kind == ATT_INPORT || t->kind == ATT_PARAMS)
            look(ws, i, now);
        i = following;
    }
    look_timed(ws, now, next);
}

static uint32_t event_count(att* t, uint32_t kind)
{
    uint32_t c = 1;
    if (kind == LN_WAIT_TIMER)
        c = t->timer_count, t->timer_count = 0;
    else if (kind == LN_WAIT_DEADLINE)
        c = t->deadline_count, t->deadline_count = 0;
    return c;
}

/* The kind to report first: a publisher that came back before its samples, one that went
 * after them. */
static uint32_t first_kind(uint32_t fired)
{
    static const uint32_t order[] = {LN_WAIT_BACK, LN_WAIT_DATA,     LN_WAIT_DEADLINE,
                                     LN_WAIT_GONE, LN_WAIT_REQUESTS, LN_WAIT_PARAMETERS,
                                     LN_WAIT_FD,   LN_WAIT_TIMER};
    for (size_t k = 0; k < sizeof order / sizeof order[0]; k++)
        if (fired & FIRE(order[k]))
            return order[k];
    return (uint32_t)__builtin_ctz(fired);
}

/* Moves fired events into ready[] (at most n); what does not fit stays fired. */
static size_t report(ln_waitset* ws, ln_waitset_event* ready, size_t n)
{
    size_t out = 0;
    uint32_t trig = 0;
    if (n > 0 && (trig = atomic_exchange_explicit(&ws->triggers, 0, memory_order_acq_rel)) != 0)
        ready[out++] =
            (ln_waitset_event){.id = LN_WAITSET_TRIGGER_ID, .kind = LN_WAIT_TRIGGER, .count = trig};
    while (out < n && ws->fired_head != NONE) {
        int i = ws->fired_head;
        att* t = &ws->a[i];
        while (out < n && t->fired) {
            uint32_t kind = first_kind(t->fired);
            t->fired &= ~FIRE(kind);
            ln_waitset_event* e = &ready[out++];
            *e = (ln_waitset_event){.id = id_of(ws, i),
                                    .kind = kind,
                                    .count = event_count(t, kind),
                                    .user_data = t->user_data};
            if (kind == LN_WAIT_FD) {
                e->events = t->fd_events;
                t->fd_events = 0;
            }
            /* level-triggered: again while unread samples remain (requests and descriptors:
             * epoll reports them again while they hold) */
            if (kind == LN_WAIT_DATA)
                push(ws, RECHECK, i);
        }
        if (t->fired == 0)
            pop_fired(ws);
    }
    return out;
}

static struct timespec span(int64_t ns)
{
    if (ns < 0)
        ns = 0;
    return (struct timespec){.tv_sec = ns / 1000000000LL, .tv_nsec = ns % 1000000000LL};
}

/* One round: collect, and if nothing is ready sleep until `until` (INT64_MAX: forever) or the
 * earliest timer; returns the number of events, 0, or LN_EINTR. */
static int wait_locked(ln_waitset* ws, int64_t until, ln_waitset_event* ready, size_t n)
{
    struct epoll_event evs[16];
    for (;;) {
        int64_t now = now_ns();
        int64_t next = until;
        collect(ws, now, &next);
        if (ws->fired_head != NONE || atomic_load_explicit(&ws->triggers, memory_order_acquire))
            return (int)report(ws, ready, n);
        struct timespec rel = span(next - now);
        int sleep = next > now;
        int got, err;
        if (ws->polled == 0 && next == INT64_MAX) {
            /* only the bell to watch, no time limit: sleep in its receive (one system call
             * per wake-up instead of epoll's two) */
            bell_batch b;
            pthread_mutex_unlock(&ws->mu);
            got = bell_receive(ws, &b, MSG_WAITFORONE);
            err = errno;
            pthread_mutex_lock(&ws->mu);
            now = now_ns();
            if (got > 0)
                bell_take(ws, &b, got, now);
        } else {
            pthread_mutex_unlock(&ws->mu);
            got = epoll_pwait2(ws->epfd, evs, 16, next == INT64_MAX ? NULL : &rel, NULL);
            err = errno;
            pthread_mutex_lock(&ws->mu);
            now = now_ns();
            for (int k = 0; k < got; k++)
                on_epoll(ws, &evs[k], now);
        }
        if (got < 0 && err == EINTR) {
            next = INT64_MAX;
            collect(ws, now, &next);
            if (ws->fired_head == NONE && !atomic_load(&ws->triggers))
                return LN_EINTR;
        }
        if (got < 0 && err != EINTR)
            return ln_set_errno_error(NULL, err, "ln_waitset_wait: waiting");
        if (ws->fired_head == NONE && !atomic_load(&ws->triggers) && now >= until &&
            (got == 0 || !sleep))
            return 0;
    }
}

int ln_waitset_wait(ln_waitset* ws, double timeout, ln_waitset_event* ready, size_t n)
{
    int rc = ws_check(ws, "ln_waitset_wait");
    if (rc != LN_OK)
        return rc;
    if (ready == NULL || n == 0 || isnan(timeout))
        return ln_set_error(NULL, LN_EINVAL,
                            "ln_waitset_wait: ready is NULL, n is 0 or the "
                            "timeout is NaN");
    int expected = 0;
    if (!atomic_compare_exchange_strong(&ws->waiting, &expected, 1))
        return ln_set_error(NULL, LN_EBUSY, "ln_waitset_wait: another thread waits already");
    int64_t until = timeout < 0 || timeout > 1e9 ? INT64_MAX : now_ns() + seconds_ns(timeout);
    pthread_mutex_lock(&ws->mu);
    rc = wait_locked(ws, until, ready, n);
    pthread_mutex_unlock(&ws->mu);
    atomic_store_explicit(&ws->waiting, 0, memory_order_seq_cst);
    return rc;
}

int ln_waitset_trigger(ln_waitset* ws)
{
    if (ws == NULL || ws->magic != LN_WAITSET_MAGIC)
        return LN_EBADHANDLE; /* no error text: this may run in a signal handler */
    atomic_fetch_add_explicit(&ws->triggers, 1, memory_order_acq_rel);
    ln_bell_ring(ws->bell, 0);
    return LN_OK;
}

int ln_waitset_fd(const ln_waitset* ws)
{
    int rc = ws_check(ws, "ln_waitset_fd");
    return rc != LN_OK ? rc : ws->epfd;
}

int ln_waitset_next_due(ln_waitset* ws, int64_t* monotonic_ns)
{
    int rc = ws_check(ws, "ln_waitset_next_due");
    if (rc != LN_OK)
        return rc;
    if (monotonic_ns == NULL)
        return ln_set_error(NULL, LN_EINVAL, "ln_waitset_next_due: monotonic_ns is NULL");
    pthread_mutex_lock(&ws->mu);
    int64_t now = now_ns();
    int64_t next = INT64_MAX;
    /* what a wait would look at first (inports reported last time: data left unread?), so
     * that an event loop is sent back only when there is something */
    collect(ws, now, &next);
    if (ws->fired_head != NONE || atomic_load_explicit(&ws->triggers, memory_order_acquire))
        next = now;
    pthread_mutex_unlock(&ws->mu);
    *monotonic_ns = next == INT64_MAX ? -1 : next;
    return LN_OK;
}
