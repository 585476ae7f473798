/* client_log.c — ln_log and friends (docs/logging.md, "Client logging"): log lines put into a
 * bounded lock-free queue of the client (the format and its arguments, log_format.h), and the
 * thread that formats them and sends them to the manager in LOG batches.  The calling thread
 * never waits and makes no system call (but on the very first line, which starts the queue
 * and its thread). */
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "client_conn.h"
#include "log_format.h"
#include "net.h"

#define LOG_FILE_MAX 256   /* bytes of a file name kept (its end), NUL included */
#define LOG_LOGGER_MAX 128 /* bytes of a logger name, NUL included */
#define LOG_BATCH 256      /* lines per LOG frame, so a frame stays far below 1 MiB */
#define LOG_IDLE_S 0.01    /* the sender looks at the queue every 10 ms when idle */

typedef struct log_entry {
    int level;
    int line;
    int nargs; /* -1: `text` is the text; else it holds a format and these arguments */
    uint64_t time_ns;
    char file[LOG_FILE_MAX];
    char logger[LOG_LOGGER_MAX];
    char text[LN_LOG_TEXT_MAX];
    ln_log_arg args[LN_LOG_MAX_ARGS];
} log_entry;

/* One slot of the queue.  Its sequence word tells who may touch it (Vyukov's bounded queue):
 * seq == pos: free for the producer that claims position pos (by a CAS on `head`); seq ==
 * pos + 1: written (release), readable by the sender (acquire); the sender frees it for the
 * next round with seq = pos + LN_LOG_QUEUE (release).  So producers never wait on each other
 * or on the sender: a full queue is a failed check, not a wait. */
typedef struct log_slot {
    _Atomic size_t seq;
    log_entry e;
} log_slot;

struct ln_log_queue {
    _Atomic size_t head; /* next position a producer claims; = lines queued */
    size_t tail;         /* next position the sender reads (sender only) */
    _Atomic size_t sent; /* positions below are sent or dropped (for ln_log_flush) */
    _Atomic uint64_t dropped;
    _Atomic int level; /* lines below are not queued */
    ln_client* clnt;
    pthread_mutex_t lock; /* for the conditions only; never taken by a producer */
    pthread_cond_t wake;  /* the sender: stop or flush asked */
    pthread_cond_t done;  /* flushers: `sent` moved */
    int stop;
    int flushing;
    pthread_t thread;
    char* batch; /* the entries text of one LOG frame */
    size_t batch_cap;
    char rendered[LN_LOG_TEXT_MAX]; /* a deferred format's text (sender only) */
    log_slot slots[LN_LOG_QUEUE];
};

_Static_assert((LN_LOG_QUEUE & (LN_LOG_QUEUE - 1)) == 0, "LN_LOG_QUEUE is a power of two");

static pthread_mutex_t log_start_lock = PTHREAD_MUTEX_INITIALIZER;

/* Makes s valid UTF-8 without the LOG separators: bytes of a bad sequence become '?', the
 * separators ' '. */
static void log_sanitize(char* s)
{
    unsigned char* p = (unsigned char*)s;
    while (*p != 0) {
        unsigned c = *p;
        size_t n = c < 0x80                          ? 1
                   : (c & 0xE0) == 0xC0 && c >= 0xC2 ? 2
                   : (c & 0xF0) == 0xE0              ? 3
                   : (c & 0xF8) == 0xF0 && c <= 0xF4 ? 4
                                                     : 0;
        size_t ok = n;
        for (size_t i = 1; i < n && ok == n; i++)
            if ((p[i] & 0xC0) != 0x80)
                ok = 0;
        if (n >= 3 && ok == n) { /* overlong, surrogates and above U+10FFFF */
            unsigned cp = n == 3 ? (c & 0x0F) << 12 | (p[1] & 0x3Fu) << 6 | (p[2] & 0x3Fu)
                                 : (c & 0x07) << 18 | (p[1] & 0x3Fu) << 12 | (p[2] & 0x3Fu) << 6 |
                                       (p[3] & 0x3Fu);
            if ((n == 3 && (cp < 0x800 || (cp >= 0xD800 && cp <= 0xDFFF))) ||
                (n == 4 && (cp < 0x10000 || cp > 0x10FFFF)))
                ok = 0;
        }
        if (ok == 0) {
            *p++ = '?';
            continue;
        }
        if (c == LN_PROTO_LOG_FIELD || c == LN_PROTO_LOG_END)
            *p = ' ';
        p += n;
    }
}

/* Copies the end of `s` (a file path keeps its name) into out[size]. */
static void log_copy_tail(char* out, size_t size, const char* s)
{
    if (s == NULL) {
        out[0] = 0;
        return;
    }
    size_t len = strlen(s);
    const char* from = len >= size ? s + len - (size - 1) : s;
    memcpy(out, from, strlen(from) + 1);
}

static void log_copy_head(char* out, size_t size, const char* s)
{
    if (s == NULL) {
        out[0] = 0;
        return;
    }
    size_t len = strnlen(s, size - 1);
    memcpy(out, s, len);
    out[len] = 0;
}

/* Appends one entry to the batch text (the caller made room), its text formatted now if it
 * was deferred; every field made fit for the wire. */
static size_t log_format_entry(struct ln_log_queue* q, char* out, size_t cap, log_entry* e)
{
    char* text = e->text;
    if (e->nargs >= 0) {
        ln_log_render(q->rendered, sizeof q->rendered, e->text, e->args, e->nargs);
        text = q->rendered;
    }
    log_sanitize(e->file);
    log_sanitize(e->logger);
    log_sanitize(text);
    int n = snprintf(out, cap, "%d%c%llu%c%s%c%d%c%s%c%s%c", e->level, LN_PROTO_LOG_FIELD,
                     (unsigned long long)e->time_ns, LN_PROTO_LOG_FIELD, e->file,
                     LN_PROTO_LOG_FIELD, e->line, LN_PROTO_LOG_FIELD, e->logger, LN_PROTO_LOG_FIELD,
                     text, LN_PROTO_LOG_END);
    return n < 0 ? 0 : (size_t)n < cap ? (size_t)n : cap - 1;
}

/* Takes up to LOG_BATCH written lines off the queue into q->batch; *count their number. */
static size_t log_drain(struct ln_log_queue* q, uint32_t* count)
{
    size_t len = 0;
    *count = 0;
    while (*count < LOG_BATCH) {
        log_slot* s = &q->slots[q->tail & (LN_LOG_QUEUE - 1)];
        size_t seq = atomic_load_explicit(&s->seq, memory_order_acquire);
        if (seq != q->tail + 1)
            break; /* empty, or its producer is still writing it */
        len += log_format_entry(q, q->batch + len, q->batch_cap - len, &s->e);
        atomic_store_explicit(&s->seq, q->tail + LN_LOG_QUEUE, memory_order_release);
        q->tail++;
        (*count)++;
    }
    q->batch[len] = 0;
    return len;
}

/* Sends what is queued; returns the lines taken off the queue. */
static uint32_t log_send_some(struct ln_log_queue* q)
{
    uint32_t count;
    size_t len = log_drain(q, &count);
    if (count == 0)
        return 0;
    ln_wbuf body;
    ln_wbuf_init(&body);
    ln_msg_log m = {.dropped = atomic_load_explicit(&q->dropped, memory_order_relaxed),
                    .count = count,
                    .entries = {q->batch, len}};
    ln_msg_log_write_after_id(&body, &m);
    uint16_t type;
    ln_rbuf reply;
    int rc = ln_client_request(q->clnt, LN_MSG_LOG, &body, &type, &reply);
    ln_wbuf_free(&body);
    if (rc != LN_OK) /* manager away: the lines are lost, and counted */
        atomic_fetch_add_explicit(&q->dropped, count, memory_order_relaxed);
    return count;
}

static void* log_sender_main(void* arg)
{
    struct ln_log_queue* q = arg;
    pthread_mutex_lock(&q->lock);
    for (;;) {
        int stop = q->stop;
        pthread_mutex_unlock(&q->lock);
        uint32_t n = log_send_some(q);
        pthread_mutex_lock(&q->lock);
        atomic_store_explicit(&q->sent, q->tail, memory_order_release);
        pthread_cond_broadcast(&q->done);
        if (n == LOG_BATCH)
            continue; /* more is waiting */
        if (stop && n == 0)
            break;
        if (!q->stop && !q->flushing) {
            struct timespec ts;
            pthread_cond_timedwait(&q->wake, &q->lock, ln_net_deadline(&ts, LOG_IDLE_S));
        }
    }
    pthread_mutex_unlock(&q->lock);
    return NULL;
}

/* The client's queue, started on first use (LN_OK), or an error code (recorded). */
static int log_queue_of(ln_client* clnt, struct ln_log_queue** out)
{
    struct ln_log_queue* q = atomic_load_explicit(&clnt->log, memory_order_acquire);
    if (q != NULL) {
        *out = q;
        return LN_OK;
    }
    int rc = LN_OK;
    pthread_mutex_lock(&log_start_lock);
    q = atomic_load_explicit(&clnt->log, memory_order_acquire);
    if (q != NULL)
        goto done;
    q = calloc(1, sizeof *q);
    char* batch = malloc((size_t)LOG_BATCH * (sizeof(log_entry) + 64));
    if (q == NULL || batch == NULL) {
        free(q);
        free(batch);
        q = NULL;
        rc = ln_set_error(clnt, LN_ENOMEM, "ln_log: out of memory for the log queue");
        goto done;
    }
    q->batch = batch;
    q->batch_cap = (size_t)LOG_BATCH * (sizeof(log_entry) + 64);
    q->clnt = clnt;
    atomic_init(&q->level, LN_LOG_DEBUG);
    for (size_t i = 0; i < LN_LOG_QUEUE; i++)
        atomic_init(&q->slots[i].seq, i);
    pthread_mutex_init(&q->lock, NULL);
    pthread_condattr_t monotonic; /* the deadlines of ln_net_deadline */
    pthread_condattr_init(&monotonic);
    pthread_condattr_setclock(&monotonic, CLOCK_MONOTONIC);
    pthread_cond_init(&q->wake, &monotonic);
    pthread_cond_init(&q->done, &monotonic);
    pthread_condattr_destroy(&monotonic);
    int err = pthread_create(&q->thread, NULL, log_sender_main, q);
    if (err != 0) {
        pthread_cond_destroy(&q->done);
        pthread_cond_destroy(&q->wake);
        pthread_mutex_destroy(&q->lock);
        free(q->batch);
        free(q);
        q = NULL;
        rc = ln_set_errno_error(clnt, err, "ln_log: cannot start the log sender thread");
        goto done;
    }
    atomic_store_explicit(&clnt->log, q, memory_order_release);
done:
    pthread_mutex_unlock(&log_start_lock);
    *out = q;
    return rc;
}

static int log_check_level(ln_client* clnt, int level)
{
    if (level < LN_LOG_DEBUG || level > LN_LOG_CRITICAL)
        return ln_set_error(clnt, LN_EINVAL, "log level %d is not in %d..%d", level, LN_LOG_DEBUG,
                            LN_LOG_CRITICAL);
    return LN_OK;
}

/* Claims a slot: its entry to fill and its position, or NULL when the queue is full. */
static log_slot* log_claim(struct ln_log_queue* q, size_t* pos_out)
{
    size_t pos = atomic_load_explicit(&q->head, memory_order_relaxed);
    for (;;) {
        log_slot* s = &q->slots[pos & (LN_LOG_QUEUE - 1)];
        size_t seq = atomic_load_explicit(&s->seq, memory_order_acquire);
        intptr_t diff = (intptr_t)seq - (intptr_t)pos;
        if (diff == 0) {
            if (atomic_compare_exchange_weak_explicit(&q->head, &pos, pos + 1, memory_order_relaxed,
                                                      memory_order_relaxed)) {
                *pos_out = pos;
                return s;
            }
        } else if (diff < 0) {
            return NULL;
        } else {
            pos = atomic_load_explicit(&q->head, memory_order_relaxed);
        }
    }
}

/* One line: `text` as it is, or else formatted from fmt and *ap. */
static int log_v(ln_client* clnt, int level, const char* file, int line, const char* logger,
                 const char* text, const char* fmt, va_list* ap)
{
    int rc = ln_client_check(clnt);
    if (rc != LN_OK)
        return rc;
    if ((rc = log_check_level(clnt, level)) != LN_OK)
        return rc;
    if (fmt == NULL && text == NULL)
        return ln_set_error(clnt, LN_EINVAL, "ln_log: the format is NULL");
    struct ln_log_queue* q;
    if ((rc = log_queue_of(clnt, &q)) != LN_OK)
        return rc;
    if (level < atomic_load_explicit(&q->level, memory_order_relaxed))
        return LN_OK;
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts); /* the vDSO: no system call */
    size_t pos;
    log_slot* s = log_claim(q, &pos);
    if (s == NULL) {
        atomic_fetch_add_explicit(&q->dropped, 1, memory_order_relaxed);
        return LN_EAGAIN; /* not recorded as an error: that would cost a lock */
    }
    log_entry* e = &s->e;
    e->level = level;
    e->line = line;
    e->time_ns = (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
    log_copy_tail(e->file, sizeof e->file, file);
    log_copy_head(e->logger, sizeof e->logger, logger);
    e->nargs = -1;
    if (text != NULL) {
        log_copy_head(e->text, sizeof e->text, text);
    } else { /* the format and its arguments; printf runs in the sender (or now, if need be) */
        va_list copy;
        va_copy(copy, *ap);
        e->nargs = ln_log_capture(e->text, sizeof e->text, e->args, fmt, &copy);
        va_end(copy);
        if (e->nargs < 0)
            vsnprintf(e->text, sizeof e->text, fmt, *ap);
    }
    atomic_store_explicit(&s->seq, pos + 1, memory_order_release);
    /* The next line most likely goes into the next slot, which was last written a whole
     * queue ago: fetch its first cache lines now, so that a loop logging once per period
     * does not pay the misses on its next call (a hint only; no system call, no wait). */
    log_slot* next = &q->slots[(pos + 1) & (LN_LOG_QUEUE - 1)];
    __builtin_prefetch(next, 1);
    __builtin_prefetch(next->e.file, 1);
    __builtin_prefetch(next->e.logger, 1);
    __builtin_prefetch(next->e.text, 1);
    __builtin_prefetch(next->e.text + 64, 1);
    __builtin_prefetch(next->e.args, 1);
    return LN_OK;
}

int ln_log(ln_client* clnt, int level, const char* fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int rc = log_v(clnt, level, NULL, 0, NULL, NULL, fmt, &ap);
    va_end(ap);
    return rc;
}

int ln_log_at(ln_client* clnt, int level, const char* file, int line, const char* fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int rc = log_v(clnt, level, file, line, NULL, NULL, fmt, &ap);
    va_end(ap);
    return rc;
}

int ln_log_text(ln_client* clnt, int level, const char* file, int line, const char* logger,
                const char* text)
{
    if (text == NULL)
        return ln_set_error(clnt, LN_EINVAL, "ln_log_text: text is NULL");
    return log_v(clnt, level, file, line, logger, text, NULL, NULL);
}

int ln_log_set_level(ln_client* clnt, int level)
{
    int rc = ln_client_check(clnt);
    if (rc != LN_OK || (rc = log_check_level(clnt, level)) != LN_OK)
        return rc;
    struct ln_log_queue* q;
    if ((rc = log_queue_of(clnt, &q)) != LN_OK)
        return rc;
    atomic_store_explicit(&q->level, level, memory_order_relaxed);
    return LN_OK;
}

int ln_log_counts(ln_client* clnt, uint64_t* queued, uint64_t* dropped)
{
    int rc = ln_client_check(clnt);
    if (rc != LN_OK)
        return rc;
    struct ln_log_queue* q = atomic_load_explicit(&clnt->log, memory_order_acquire);
    if (queued != NULL)
        *queued = q == NULL ? 0 : atomic_load_explicit(&q->head, memory_order_relaxed);
    if (dropped != NULL)
        *dropped = q == NULL ? 0 : atomic_load_explicit(&q->dropped, memory_order_relaxed);
    return LN_OK;
}

/* Waits until the sender has passed `target`, or the deadline (NULL: none). */
static int log_wait_sent(struct ln_log_queue* q, size_t target, const struct timespec* deadline)
{
    int rc = LN_OK;
    pthread_mutex_lock(&q->lock);
    q->flushing++;
    pthread_cond_signal(&q->wake);
    while (atomic_load_explicit(&q->sent, memory_order_acquire) < target) {
        int err = deadline != NULL ? pthread_cond_timedwait(&q->done, &q->lock, deadline)
                                   : pthread_cond_wait(&q->done, &q->lock);
        if (err == ETIMEDOUT) {
            rc = LN_ETIMEOUT;
            break;
        }
    }
    q->flushing--;
    pthread_mutex_unlock(&q->lock);
    return rc;
}

int ln_log_flush(ln_client* clnt, double timeout)
{
    int rc = ln_client_check(clnt);
    if (rc != LN_OK)
        return rc;
    if (isnan(timeout))
        return ln_set_error(clnt, LN_EINVAL, "ln_log_flush: timeout is NaN");
    struct ln_log_queue* q = atomic_load_explicit(&clnt->log, memory_order_acquire);
    if (q == NULL)
        return LN_OK;
    struct timespec ts;
    rc = log_wait_sent(q, atomic_load_explicit(&q->head, memory_order_acquire),
                       ln_net_deadline(&ts, timeout));
    if (rc != LN_OK)
        return ln_set_error(clnt, rc, "ln_log_flush: lines still queued after %g s", timeout);
    return LN_OK;
}

void ln_log_stop(ln_client* clnt)
{
    struct ln_log_queue* q = atomic_load_explicit(&clnt->log, memory_order_acquire);
    if (q == NULL)
        return;
    pthread_mutex_lock(&q->lock);
    q->stop = 1;
    pthread_cond_signal(&q->wake);
    pthread_mutex_unlock(&q->lock);
    pthread_join(q->thread, NULL);
    atomic_store_explicit(&clnt->log, NULL, memory_order_release);
    pthread_cond_destroy(&q->done);
    pthread_cond_destroy(&q->wake);
    pthread_mutex_destroy(&q->lock);
    free(q->batch);
    free(q);
}
