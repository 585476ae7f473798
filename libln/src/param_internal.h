/* param_internal.h — parameter blocks inside libln (docs/parameters.md).  param_block.c owns
 * the handle and the real-time update; param_value.c the types and the checking and
 * writing of values; param_service.c the block's service (list/get/set/reset) and the
 * initial overrides of $LN_PARAMETERS.  Never installed.
 *
 * Concurrency: the service side (requests, under `lock`) keeps the authoritative overrides
 * and hands complete copies to the loop through a triple buffer: it fills `back`, then swaps
 * it with `middle` (atomic exchange, DIRTY bit set); update() swaps `middle` with its
 * `front` only when DIRTY is set.  So update() reads one atomic word when nothing changed,
 * never waits and never sees half of a request.  Live values for `get` travel the other
 * way on request: the service side sets report_state to REQUESTED, the next update() copies
 * inputs and outputs into the report buffers and sets DONE (or the service side takes the
 * request back after its wait with a CAS). */
#ifndef LN_PARAM_INTERNAL_H
#define LN_PARAM_INTERNAL_H

#include <pthread.h>
#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>

#include "ln_internal.h"
#include "param_json.h"

#define LN_PARAM_MAGIC 0x4c4e5042u
#define LN_PARAM_DIRTY 0x4u                   /* in `middle`: a newer copy waits for the loop */
#define LN_PARAM_MAX_COUNT (1u << 20)         /* elements of one parameter */
#define LN_PARAM_MAX_BYTES ((size_t)16 << 20) /* value bytes of one block */
#define LN_PARAM_REASON_MAX 512
#define LN_PARAM_GROUP "ln.parameters" /* the service group and thread pool of every block */
#define LN_PARAM_HISTORY 64            /* changes a block remembers (op "changes") */
#define LN_PARAM_HISTORY_VALUES 4096   /* bytes of values a remembered change keeps at most */
#define LN_PARAM_MD "ln/parameters/query"

enum ln_param_kind { LN_PK_CHAR, LN_PK_INT, LN_PK_UINT, LN_PK_FLOAT };

typedef struct ln_param_type {
    const char* name; /* md name */
    enum ln_param_kind kind;
    size_t size;
} ln_param_type;

enum { LN_REPORT_IDLE, LN_REPORT_REQUESTED, LN_REPORT_WRITING, LN_REPORT_DONE };

/* What the loop needs of a parameter, packed for update(). */
typedef struct ln_param_rt {
    const void* input; /* NULL: the default */
    void* output;
    size_t size, offset;
    uint64_t gen;       /* generation of the override state it applied */
    uint8_t overridden; /* as applied */
    uint8_t changed;    /* in the last update() */
} ln_param_rt;

/* The service side's view of a parameter (under the block's lock). */
typedef struct ln_param {
    char name[LN_PARAMETER_MAX_NAME + 1];
    const ln_param_type* type;
    uint32_t count, flags;
    size_t size, offset;
    char* description;
    double min, max;
    int has_input;
    int overridden;
    uint64_t gen;       /* block generation of its last change, 0: never */
    const char* source; /* of the override: "set" or "config" */
} ln_param;

/* One remembered change: its generation, CLOCK_REALTIME, op and a JSON fragment
 * `"parameters": [...], "values": {...}` (values only for a set that fits). */
typedef struct ln_param_change {
    uint64_t gen;
    int64_t time_ns;
    const char* op; /* "set", "config", "reset" */
    char* json;
} ln_param_change;

/* One copy of the override state, as the loop uses it. */
typedef struct ln_param_snap {
    uint64_t* gens;
    uint8_t* overridden;
    uint8_t* values;
} ln_param_snap;

struct ln_parameter_block {
    uint32_t magic;
    ln_client* clnt;
    char name[LN_PARAMETER_MAX_NAME + 1];
    char service[256];
    ln_param* params;
    ln_param_rt* rt;
    uint32_t n, cap;
    size_t values_size;
    int registered;
    ln_service_provider* provider;
    ln_parameter_validator validator;
    void* validator_user;

    /* service side */
    pthread_mutex_t lock;
    uint64_t generation; /* of the last change */
    uint8_t* values;     /* the overrides (those of params[i].overridden) */
    uint8_t* defaults;   /* the value of a parameter without input, taken at add() */
    uint8_t* known_in;   /* inputs and outputs as of the last report (or registration) */
    uint8_t* known_out;
    uint64_t known_update;                     /* update() count of that report, 0: registration */
    char* config_errors;                       /* JSON array of texts: refused initial overrides */
    ln_param_change history[LN_PARAM_HISTORY]; /* ring: change gen lives at gen % size */
    uint32_t back;

    /* the loop's */
    ln_param_snap snaps[3];
    uint32_t front;
    uint64_t rt_updates;
    int rt_any_changed;
    _Atomic uint32_t middle;
    _Atomic uint64_t updates;     /* update() calls so far */
    _Atomic uint64_t applied_gen; /* block generation the loop has taken */

    /* a waitset attached to it (waitset.c): rung when overrides are handed to the loop */
    ln_waitset* ws; /* under `lock` */
    _Atomic uint64_t bell;
    _Atomic uint32_t bell_tag; /* the attachment's id, which the bell carries */

    /* reports */
    _Atomic uint32_t report_state;
    uint8_t* report_in;
    uint8_t* report_out;
    uint64_t report_update;
};

/* ---- param_value.c ---- */
/* The type of md primitive `name` (aliases included), NULL if there is none. */
const ln_param_type* ln_param_type_find(const char* name);

/* Why a value was refused: kind is one of not_found, type, size, range, read_only, refused,
 * bad_request; code the LN_E* code the setter gets. */
typedef struct ln_param_err {
    const char* kind;
    int code;
    char reason[LN_PARAM_REASON_MAX];
} ln_param_err;
/* Records a refusal; returns -1 for `return ln_param_fail(...)`. */
int ln_param_fail(ln_param_err* err, const char* kind, const char* fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* Reads the JSON value at *cursor for parameter p into dst (p->size bytes): the type and
 * element count must fit (an integer is fine for a float, a whole number for an integer,
 * "NaN"/"Infinity"/"-Infinity" for a float), then the range.  0, or -1 with err set. */
int ln_param_parse(const ln_param* p, const char** cursor, void* dst, ln_param_err* err);
/* Every check of a value about to be taken: ln_param_parse, read-only, the validator. */
int ln_param_check(ln_parameter_block* blk, uint32_t index, const char** cursor, void* dst,
                   ln_param_err* err);
/* Writes the value src (p->size bytes) of p as JSON: a number, a string for char, an array
 * for count > 1. */
void ln_param_write(ln_pbuf* b, const ln_param* p, const void* src);

/* ---- param_block.c ---- */
/* A block without checks and without registering it on its client (clnt may be NULL: the
 * unit tests).  NULL when out of memory. */
ln_parameter_block* ln_param_new(ln_client* clnt, const char* name, const char* service);
/* Everything of register but the service: allocates the copies, takes $LN_PARAMETERS. */
int ln_param_prepare(ln_parameter_block* blk);
/* Copies the service side's override state into `back` and hands it to the loop (lock held). */
void ln_param_publish(ln_parameter_block* blk);
/* The index of parameter `name`, -1 if there is none. */
int ln_param_find(const ln_parameter_block* blk, const char* name);

/* ---- param_history.c ---- */
/* Remembers the change of generation blk->generation (lock held): `op`, the parameters
 * marked in `which` and, for a set, their new values in `values` (the value area layout). */
void ln_param_history_add(ln_parameter_block* blk, const char* op, const uint8_t* which,
                          const uint8_t* values);
/* The answer to "changes": {"generation", "oldest", "changes": [...]} of the remembered
 * changes after generation `since`, oldest first. */
void ln_param_history_write(const ln_parameter_block* blk, uint64_t since, ln_pbuf* out);
void ln_param_history_free(ln_parameter_block* blk);

/* ---- param_service.c ---- */
/* The handler of the block's service. */
int ln_param_handle(ln_client* clnt, ln_service_request* call, void* blk);
/* One request as the handler carries it out (takes the lock): 0 with the result's JSON in
 * out, or -1 with err set. */
int ln_param_request(ln_parameter_block* blk, const char* op, const char* name, const char* value,
                     ln_pbuf* out, ln_param_err* err);
/* Takes the block's initial overrides from $LN_PARAMETERS (before it is registered). */
void ln_param_configure(ln_parameter_block* blk);

#endif /* LN_PARAM_INTERNAL_H */
