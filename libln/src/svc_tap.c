/* svc_tap.c — the provider's side of recording calls (svc_tap.h): bounded per-recorder queues
 * filled by the threads that answer calls and emptied by one sender thread per provider, which
 * is the only one that ever writes to a recorder's socket.  A recorder that is slow loses calls
 * (counted in the next CALL it gets); one that is gone is forgotten at its next write or when
 * its connection reports the hang-up, whichever comes first. */
#include <errno.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "net.h"
#include "svc_internal.h"

#define DROPPED_OFFSET (LN_SVC_HEADER_SIZE + 16) /* after the header and two u64 */

typedef struct tap_rec {
    struct tap_rec* next;
    size_t len;
    uint8_t data[]; /* a whole CALL frame */
} tap_rec;

typedef struct tap {
    struct tap* next;
    int64_t id;
    int fd;
    int dead; /* forget it (hang-up or a failed write) */
    tap_rec *head, *tail;
    size_t calls, bytes;
    uint64_t dropped;
} tap;

struct ln_svc_taps {
    pthread_mutex_t lock;
    pthread_cond_t more;
    pthread_t thread;
    int started, stop;
    int64_t next_id;
    tap* list;
};

ln_svc_taps* ln_svc_taps_new(void)
{
    ln_svc_taps* t = calloc(1, sizeof *t);
    if (t == NULL)
        return NULL;
    pthread_mutex_init(&t->lock, NULL);
    pthread_cond_init(&t->more, NULL);
    return t;
}

static void tap_free(tap* x)
{
    while (x->head != NULL) {
        tap_rec* r = x->head;
        x->head = r->next;
        free(r);
    }
    close(x->fd);
    free(x);
}

/* Lock held: unlinks the dead taps (freed by the caller after unlocking) and counts the live. */
static tap* unlink_dead(ln_service_provider* p)
{
    ln_svc_taps* t = p->taps;
    tap *dead = NULL, **at = &t->list;
    int live = 0;
    while (*at != NULL) {
        tap* x = *at;
        if (x->dead) {
            *at = x->next;
            x->next = dead;
            dead = x;
        } else {
            live++;
            at = &x->next;
        }
    }
    atomic_store(&p->tapped, live);
    return dead;
}

static void free_list(tap* x)
{
    while (x != NULL) {
        tap* next = x->next;
        tap_free(x);
        x = next;
    }
}

/* Lock held: a live tap with a queued call, or NULL. */
static tap* ready(ln_svc_taps* t)
{
    for (tap* x = t->list; x != NULL; x = x->next)
        if (!x->dead && x->head != NULL)
            return x;
    return NULL;
}

static void* sender(void* arg)
{
    ln_service_provider* p = arg;
    ln_svc_taps* t = p->taps;
    pthread_mutex_lock(&t->lock);
    while (!t->stop) {
        tap* dead = unlink_dead(p);
        if (dead != NULL) {
            pthread_mutex_unlock(&t->lock);
            free_list(dead);
            pthread_mutex_lock(&t->lock);
            continue;
        }
        tap* x = ready(t);
        if (x == NULL) {
            pthread_cond_wait(&t->more, &t->lock);
            continue;
        }
        tap_rec* r = x->head;
        x->head = r->next;
        if (x->head == NULL)
            x->tail = NULL;
        x->calls--;
        x->bytes -= r->len;
        for (int i = 0; i < 8; i++)
            r->data[DROPPED_OFFSET + i] = (uint8_t)(x->dropped >> (8 * i));
        int fd = x->fd;
        /* Unlocked while writing: x stays (only this thread frees taps, hangups only mark). */
        pthread_mutex_unlock(&t->lock);
        struct timespec deadline;
        int err = ln_net_write_all(fd, r->data, r->len,
                                   ln_net_deadline(&deadline, LN_SVC_SEND_TIMEOUT), -1);
        free(r);
        pthread_mutex_lock(&t->lock);
        if (err != 0)
            x->dead = 1;
    }
    pthread_mutex_unlock(&t->lock);
    return NULL;
}

int64_t ln_svc_tap_add(ln_service_provider* p, int fd)
{
    ln_svc_taps* t = p->taps;
    tap* x = calloc(1, sizeof *x);
    if (x == NULL) {
        close(fd);
        return LN_ENOMEM;
    }
    x->fd = fd;
    pthread_mutex_lock(&t->lock);
    if (!t->started) {
        if (pthread_create(&t->thread, NULL, sender, p) != 0) {
            pthread_mutex_unlock(&t->lock);
            tap_free(x);
            return LN_ESYS;
        }
        t->started = 1;
    }
    x->id = ++t->next_id;
    x->next = t->list;
    t->list = x;
    atomic_fetch_add(&p->tapped, 1);
    pthread_mutex_unlock(&t->lock);
    return x->id;
}

void ln_svc_tap_hangup(ln_service_provider* p, int64_t id)
{
    ln_svc_taps* t = p->taps;
    pthread_mutex_lock(&t->lock);
    for (tap* x = t->list; x != NULL; x = x->next)
        if (x->id == id && !x->dead) {
            x->dead = 1;
            atomic_fetch_sub(&p->tapped, 1);
        }
    pthread_cond_signal(&t->more);
    pthread_mutex_unlock(&t->lock);
}

static int64_t clock_ns(clockid_t clock)
{
    struct timespec ts;
    clock_gettime(clock, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

/* The CALL frame of one call (its dropped count is filled in when sent), or NULL. */
static tap_rec* make_record(const ln_service_request* req, int code, const void* answer,
                            size_t answer_len)
{
    ln_wbuf b;
    ln_wbuf_init(&b);
    size_t start = ln_proto_frame_begin(&b, LN_SVC_CALL);
    ln_wbuf_u64(&b, (uint64_t)req->t_real_ns);
    ln_wbuf_u64(&b, (uint64_t)(clock_ns(CLOCK_MONOTONIC) - req->t_mono_ns));
    ln_wbuf_u64(&b, 0);
    ln_wbuf_i32(&b, code);
    ln_wbuf_str(&b, req->ep->caller);
    ln_wbuf_u32(&b, (uint32_t)req->wire_len);
    ln_wbuf_bytes(&b, req->wire, req->wire_len);
    ln_wbuf_u32(&b, (uint32_t)answer_len);
    ln_wbuf_bytes(&b, answer, answer_len);
    tap_rec* r = NULL;
    if (ln_svc_frame_end(&b, start) == LN_OK && (r = malloc(sizeof *r + b.len)) != NULL) {
        r->next = NULL;
        r->len = b.len;
        memcpy(r->data, b.data, b.len);
    }
    ln_wbuf_free(&b);
    return r;
}

void ln_svc_tap_call(ln_service_provider* p, const ln_service_request* req, int code,
                     const void* answer, size_t answer_len)
{
    if (req->t_mono_ns == 0)
        return; /* the tap came while this call ran: it records the calls after it */
    tap_rec* r = make_record(req, code, answer, answer_len);
    ln_svc_taps* t = p->taps;
    pthread_mutex_lock(&t->lock);
    for (tap* x = t->list; x != NULL; x = x->next) {
        if (x->dead)
            continue;
        int fits = r != NULL && (x->head == NULL || (x->calls < LN_SVC_TAP_QUEUE_CALLS &&
                                                     x->bytes + r->len <= LN_SVC_TAP_QUEUE_BYTES));
        tap_rec* copy = NULL;
        if (fits && (copy = malloc(sizeof *r + r->len)) != NULL)
            memcpy(copy, r, sizeof *r + r->len);
        if (copy == NULL) {
            x->dropped++;
            continue;
        }
        if (x->tail != NULL)
            x->tail->next = copy;
        else
            x->head = copy;
        x->tail = copy;
        x->calls++;
        x->bytes += copy->len;
    }
    pthread_cond_signal(&t->more);
    pthread_mutex_unlock(&t->lock);
    free(r);
}

void ln_svc_taps_free(ln_service_provider* p)
{
    ln_svc_taps* t = p->taps;
    if (t == NULL)
        return;
    pthread_mutex_lock(&t->lock);
    t->stop = 1;
    for (tap* x = t->list; x != NULL; x = x->next)
        shutdown(x->fd, SHUT_RDWR); /* ends a write in progress */
    pthread_cond_signal(&t->more);
    int started = t->started;
    pthread_mutex_unlock(&t->lock);
    if (started)
        pthread_join(t->thread, NULL);
    free_list(t->list);
    atomic_store(&p->tapped, 0);
    pthread_mutex_destroy(&t->lock);
    pthread_cond_destroy(&t->more);
    free(t);
    p->taps = NULL;
}
