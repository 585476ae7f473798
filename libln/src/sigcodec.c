/* sigcodec.c — signature parser and wire encoder/decoder of sigcodec.h.
 * The decoder treats its input as hostile: every read is bounds-checked, every size product
 * is overflow-checked, and a dynamic count is checked against the bytes left before anything
 * is allocated for it. */
#include <assert.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "client_internal.h"
#include "sigcodec.h"

/* Dynamic fields store a raw pointer in the packed struct (docs/message_definitions.md). */
_Static_assert(sizeof(void*) == 8, "the message layout assumes 64-bit pointers");

/* ---- signature tree --------------------------------------------------------------------- */

static const struct {
    const char* name;
    size_t size;
} prims[] = {
    {"char", 1},     {"int8_t", 1},  {"uint8_t", 1},  {"int16_t", 2},
    {"uint16_t", 2}, {"int32_t", 4}, {"uint32_t", 4}, {"int64_t", 8},
    {"uint64_t", 8}, {"float", 4},   {"double", 8},
};
enum { PRIM_CHAR = 0, PRIM_UINT32 = 6, PRIM_RECORD = -1 };

typedef struct sig_item {
    int prim;             /* index into prims[], or PRIM_RECORD */
    int dynamic;          /* a count + pointer pair */
    unsigned index;       /* 1-based item number at its level (the "*" item for dynamic) */
    uint32_t count;       /* static array length; 1 for dynamic */
    size_t offset;        /* in the struct: of the data, or of the u32 count if dynamic */
    size_t elem_size;     /* in-memory bytes of one element */
    size_t elem_wire_min; /* fewest wire bytes one element can take */
    ln_sig* record;       /* element layout if prim == PRIM_RECORD; owned */
} sig_item;

struct ln_sig {
    sig_item* items;
    size_t n, cap;
    size_t size;     /* in-memory bytes */
    size_t wire_min; /* fewest wire bytes */
    int has_dynamic; /* a dynamic field anywhere inside: cannot be copied as a block */
};

void ln_sig_free(ln_sig* sig)
{
    if (sig == NULL)
        return;
    for (size_t i = 0; i < sig->n; i++)
        ln_sig_free(sig->items[i].record);
    free(sig->items);
    free(sig);
}

size_t ln_sig_size(const ln_sig* sig) { return sig->size; }

/* ---- parser ----------------------------------------------------------------------------- */

typedef struct parser {
    const char* text;
    const char* p;
    int depth;
} parser;

static int parse_error(const parser* ps, const char* at, const char* fmt, ...)
    __attribute__((format(printf, 3, 4)));

static int parse_error(const parser* ps, const char* at, const char* fmt, ...)
{
    char what[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    return ln_set_error(NULL, LN_EMD, "signature column %zu: %s (at \"%.20s\")",
                        (size_t)(at - ps->text) + 1, what, at);
}

/* Describes the character at p for "found ..." texts. */
static const char* found(const char* p, char buf[8])
{
    if (*p == '\0')
        return "end of signature";
    snprintf(buf, 8, "'%c'", *p);
    return buf;
}

static int parse_number(parser* ps, const char* what, size_t* out)
{
    const char* start = ps->p;
    size_t v = 0;
    if (*ps->p < '0' || *ps->p > '9') {
        char b[8];
        return parse_error(ps, start, "expected the %s, found %s", what, found(ps->p, b));
    }
    while (*ps->p >= '0' && *ps->p <= '9') {
        v = v * 10 + (size_t)(*ps->p - '0');
        if (v > LN_SIG_MAX_SIZE)
            return parse_error(ps, start, "%s larger than %zu", what, LN_SIG_MAX_SIZE);
        ps->p++;
    }
    *out = v;
    return LN_OK;
}

static int expect_space(parser* ps, const char* before)
{
    if (*ps->p != ' ') {
        char b[8];
        return parse_error(ps, ps->p, "expected ' ' before the %s, found %s", before,
                           found(ps->p, b));
    }
    ps->p++;
    return LN_OK;
}

static int sig_push(ln_sig* sig, const sig_item* it)
{
    if (sig->n == sig->cap) {
        size_t cap = sig->cap ? sig->cap * 2 : 8;
        sig_item* items = realloc(sig->items, cap * sizeof *items);
        if (items == NULL)
            return ln_set_error(NULL, LN_ENOMEM, "signature: out of memory");
        sig->items = items;
        sig->cap = cap;
    }
    sig->items[sig->n++] = *it;
    return LN_OK;
}

static int parse_items(parser* ps, ln_sig* sig, char end);

/* One `elem[*] SIZE COUNT` item, appended to sig (a dynamic one replaces its count item). */
static int parse_item(parser* ps, ln_sig* sig, unsigned index)
{
    const char* start = ps->p;
    sig_item it = {.prim = PRIM_RECORD, .index = index};
    int rc;
    char b[8];

    if (*ps->p == '[') {
        if (ps->depth >= LN_SIG_MAX_DEPTH)
            return parse_error(ps, start, "records nested deeper than %d", LN_SIG_MAX_DEPTH);
        ps->p++;
        if (*ps->p == ']')
            return parse_error(ps, start, "empty record");
        it.record = calloc(1, sizeof *it.record);
        if (it.record == NULL)
            return ln_set_error(NULL, LN_ENOMEM, "signature: out of memory");
        ps->depth++;
        rc = parse_items(ps, it.record, ']');
        ps->depth--;
        if (rc != LN_OK)
            goto fail;
        ps->p++; /* the ']' */
        it.elem_size = it.record->size;
        it.elem_wire_min = it.record->wire_min;
    } else {
        size_t len = strcspn(ps->p, " *,[]|");
        for (size_t i = 0; i < LN_ARRAY_SIZE(prims); i++)
            if (strlen(prims[i].name) == len && memcmp(prims[i].name, ps->p, len) == 0)
                it.prim = (int)i;
        if (len == 0)
            return parse_error(ps, start, "expected a type or '[', found %s", found(ps->p, b));
        if (it.prim == PRIM_RECORD)
            return parse_error(ps, start, "unknown type '%.*s'", (int)(len > 32 ? 32 : len), ps->p);
        ps->p += len;
        it.elem_size = it.elem_wire_min = prims[it.prim].size;
    }
    if (*ps->p == '*') {
        it.dynamic = 1;
        ps->p++;
    }

    size_t size, count;
    const char* size_at;
    const char* count_at;
    if ((rc = expect_space(ps, "size")) != LN_OK)
        goto fail;
    size_at = ps->p;
    if ((rc = parse_number(ps, "size", &size)) != LN_OK)
        goto fail;
    if ((rc = expect_space(ps, "count")) != LN_OK)
        goto fail;
    count_at = ps->p;
    if ((rc = parse_number(ps, "count", &count)) != LN_OK)
        goto fail;

    if (size != it.elem_size) {
        if (it.record != NULL)
            rc = parse_error(ps, size_at, "record size %zu, but its items take %zu bytes", size,
                             it.elem_size);
        else
            rc = parse_error(ps, size_at, "size of %s is %zu, not %zu", prims[it.prim].name,
                             it.elem_size, size);
        goto fail;
    }
    if (count == 0 || count > UINT32_MAX) {
        rc = parse_error(ps, count_at, "count must be at least 1");
        goto fail;
    }
    it.count = (uint32_t)count;

    size_t add; /* in-memory bytes this item adds to the struct */
    if (it.dynamic) {
        sig_item* prev = sig->n ? &sig->items[sig->n - 1] : NULL;
        if (count != 1) {
            rc = parse_error(ps, count_at, "a dynamic field has count 1, not %zu", count);
            goto fail;
        }
        if (prev == NULL || prev->dynamic || prev->prim != PRIM_UINT32 || prev->count != 1) {
            rc = parse_error(ps, start, "dynamic field without its 'uint32_t 4 1' count before it");
            goto fail;
        }
        it.offset = prev->offset;
        sig->n--; /* the count item becomes part of the dynamic one */
        add = 8;  /* the pointer; the count's 4 bytes (memory and wire) are counted */
        sig->has_dynamic = 1;
    } else {
        it.offset = sig->size;
        if (it.elem_size > LN_SIG_MAX_SIZE / count) {
            rc = parse_error(ps, count_at, "item larger than %zu bytes", LN_SIG_MAX_SIZE);
            goto fail;
        }
        add = it.elem_size * count;
        sig->wire_min += it.elem_wire_min * count; /* <= add, so no overflow */
        if (it.record != NULL && it.record->has_dynamic)
            sig->has_dynamic = 1;
    }
    if (add > LN_SIG_MAX_SIZE - sig->size) {
        rc = parse_error(ps, start, "struct larger than %zu bytes", LN_SIG_MAX_SIZE);
        goto fail;
    }
    sig->size += add;
    if ((rc = sig_push(sig, &it)) != LN_OK)
        goto fail;
    return LN_OK;

fail:
    ln_sig_free(it.record);
    return rc;
}

/* Items up to `end` ('\0' or ']'), which is left unconsumed. */
static int parse_items(parser* ps, ln_sig* sig, char end)
{
    for (unsigned index = 1;; index++) {
        int rc = parse_item(ps, sig, index);
        if (rc != LN_OK)
            return rc;
        if (*ps->p == end)
            return LN_OK;
        if (*ps->p != ',') {
            char b[8];
            return parse_error(ps, ps->p, "expected ',' or %s, found %s", end ? "']'" : "the end",
                               found(ps->p, b));
        }
        ps->p++;
    }
}

int ln_sig_parse(const char* signature, ln_sig** out)
{
    assert(signature != NULL && out != NULL);
    *out = NULL;
    ln_sig* sig = calloc(1, sizeof *sig);
    if (sig == NULL)
        return ln_set_error(NULL, LN_ENOMEM, "signature: out of memory");
    parser ps = {.text = signature, .p = signature};
    if (*signature != '\0') { /* "" is the empty section */
        int rc = parse_items(&ps, sig, '\0');
        if (rc != LN_OK) {
            ln_sig_free(sig);
            return rc;
        }
    }
    *out = sig;
    return LN_OK;
}

int ln_sig_split(const char* signature, char** request, char** response)
{
    assert(signature != NULL && request != NULL && response != NULL);
    *request = *response = NULL;
    const char* bar = strchr(signature, '|');
    if (bar == NULL)
        return ln_set_error(NULL, LN_EMD, "signature: no '|' between request and response");
    if (strchr(bar + 1, '|') != NULL)
        return ln_set_error(NULL, LN_EMD, "signature column %zu: a second '|'",
                            (size_t)(strchr(bar + 1, '|') - signature) + 1);
    *request = strndup(signature, (size_t)(bar - signature));
    *response = strdup(bar + 1);
    if (*request == NULL || *response == NULL) {
        free(*request);
        free(*response);
        *request = *response = NULL;
        return ln_set_error(NULL, LN_ENOMEM, "signature: out of memory");
    }
    return LN_OK;
}

/* ---- item paths for error texts --------------------------------------------------------- */

typedef struct frame {
    unsigned index; /* item number */
    long elem;      /* element number, -1 for a scalar */
} frame;

typedef struct codec {
    frame path[LN_SIG_MAX_DEPTH + 1];
    int depth;
    size_t max;
    /* encode */
    ln_wbuf* out;
    size_t start;
    /* decode */
    const uint8_t* p;
    size_t left;
    ln_arena* arena;
    size_t allocated;
} codec;

/* "item 3[2].item 5" for item `it` at the current depth. */
static const char* path_text(const codec* c, const sig_item* it, char* buf, size_t size)
{
    size_t used = 0;
    buf[0] = '\0';
    for (int i = 0; i < c->depth && used < size; i++) {
        int n = c->path[i].elem < 0
                    ? snprintf(buf + used, size - used, "item %u.", c->path[i].index)
                    : snprintf(buf + used, size - used, "item %u[%ld].", c->path[i].index,
                               c->path[i].elem);
        if (n < 0)
            break;
        used += (size_t)n;
    }
    if (used < size)
        snprintf(buf + used, size - used, "item %u", it->index);
    return buf;
}

static void push(codec* c, const sig_item* it, size_t k)
{
    assert(c->depth < (int)LN_ARRAY_SIZE(c->path));
    c->path[c->depth].index = it->index;
    c->path[c->depth].elem = it->dynamic || it->count > 1 ? (long)k : -1;
    c->depth++;
}

/* ---- encoder ---------------------------------------------------------------------------- */

/* LN_OK if `need` more bytes stay within max, else LN_ETOOBIG. */
static int enc_room(codec* c, const sig_item* it, size_t need)
{
    size_t used = c->out->len - c->start;
    if (need > c->max - used) {
        char at[256];
        return ln_set_error(NULL, LN_ETOOBIG,
                            "encoding %s: %zu more bytes after %zu exceed the limit of %zu",
                            path_text(c, it, at, sizeof at), need, used, c->max);
    }
    return LN_OK;
}

static int enc_record(codec* c, const ln_sig* sig, const uint8_t* mem)
{
    int rc;
    for (size_t i = 0; i < sig->n; i++) {
        const sig_item* it = &sig->items[i];
        const uint8_t* at = mem + it->offset;
        int walk = it->record != NULL && it->record->has_dynamic;
        size_t n = it->count;
        const uint8_t* elems = at;

        if (it->dynamic) {
            uint32_t count;
            memcpy(&count, at, sizeof count);
            memcpy(&elems, at + 4, sizeof elems);
            if (count > 0 && elems == NULL) {
                char p[256];
                return ln_set_error(NULL, LN_EINVAL,
                                    "encoding %s: dynamic field has %u elements but a NULL "
                                    "pointer",
                                    path_text(c, it, p, sizeof p), count);
            }
            if ((rc = enc_room(c, it, 4)) != LN_OK)
                return rc;
            ln_wbuf_u32(c->out, count);
            n = count;
        }
        if (walk) {
            for (size_t k = 0; k < n; k++) {
                push(c, it, k);
                rc = enc_record(c, it->record, elems + k * it->elem_size);
                c->depth--;
                if (rc != LN_OK)
                    return rc;
            }
        } else {
            size_t bytes;
            if (__builtin_mul_overflow(n, it->elem_size, &bytes))
                bytes = SIZE_MAX;
            if ((rc = enc_room(c, it, bytes)) != LN_OK)
                return rc;
            ln_wbuf_bytes(c->out, elems, bytes);
        }
        if (c->out->failed)
            return ln_set_error(NULL, c->out->failed, "encoding: %s", ln_strerror(c->out->failed));
    }
    return LN_OK;
}

int ln_sig_encode(const ln_sig* sig, const void* msg, ln_wbuf* out, size_t max_bytes)
{
    assert(sig != NULL && out != NULL && (msg != NULL || sig->size == 0));
    if (out->failed)
        return ln_set_error(NULL, out->failed, "encoding: the output buffer had failed");
    codec c = {.max = max_bytes, .out = out, .start = out->len};
    int rc = enc_record(&c, sig, msg);
    if (rc != LN_OK) {
        out->len = c.start;
        out->failed = 0;
    }
    return rc;
}

/* ---- decoder ---------------------------------------------------------------------------- */

/* Copies n wire bytes to dst, or LN_EPROTOCOL naming the item if fewer are left. */
static int dec_take(codec* c, const sig_item* it, void* dst, size_t n, const char* what)
{
    if (n > c->left) {
        char p[256];
        return ln_set_error(NULL, LN_EPROTOCOL,
                            "decoding %s: truncated, %s needs %zu bytes but %zu are left",
                            path_text(c, it, p, sizeof p), what, n, c->left);
    }
    if (n > 0)
        memcpy(dst, c->p, n);
    c->p += n;
    c->left -= n;
    return LN_OK;
}

static int dec_record(codec* c, const ln_sig* sig, uint8_t* mem);

static int dec_dynamic(codec* c, const sig_item* it, uint8_t* at)
{
    char p[256];
    uint32_t count = 0;
    uint8_t* elems = NULL;
    int rc = dec_take(c, it, &count, sizeof count, "the element count");
    if (rc != LN_OK)
        return rc;
    /* Before allocating: can the bytes left hold `count` elements at all? */
    size_t wire_min;
    if (__builtin_mul_overflow((size_t)count, it->elem_wire_min, &wire_min) || wire_min > c->left)
        return ln_set_error(NULL, LN_EPROTOCOL,
                            "decoding %s: count %u needs at least %zu bytes per element, "
                            "only %zu bytes are left",
                            path_text(c, it, p, sizeof p), count, it->elem_wire_min, c->left);
    if (count > 0) {
        size_t bytes, alloc;
        if (__builtin_mul_overflow((size_t)count, it->elem_size, &bytes) ||
            __builtin_add_overflow(bytes, it->prim == PRIM_CHAR ? 1 : 0, &alloc) ||
            alloc > c->max - c->allocated)
            return ln_set_error(NULL, LN_ETOOBIG,
                                "decoding %s: %u elements would exceed the limit of %zu bytes "
                                "(%zu already used)",
                                path_text(c, it, p, sizeof p), count, c->max, c->allocated);
        elems = ln_arena_alloc(c->arena, alloc);
        if (elems == NULL)
            return ln_set_error(NULL, LN_ENOMEM, "decoding %s: out of memory for %zu bytes",
                                path_text(c, it, p, sizeof p), alloc);
        c->allocated += alloc;
        if (it->record != NULL && it->record->has_dynamic) {
            for (size_t k = 0; k < count; k++) {
                push(c, it, k);
                rc = dec_record(c, it->record, elems + k * it->elem_size);
                c->depth--;
                if (rc != LN_OK)
                    return rc;
            }
        } else if ((rc = dec_take(c, it, elems, bytes, "the elements")) != LN_OK) {
            return rc;
        }
        if (it->prim == PRIM_CHAR)
            elems[bytes] = '\0';
    }
    memcpy(at, &count, sizeof count);
    memcpy(at + 4, &elems, sizeof elems);
    return LN_OK;
}

static int dec_record(codec* c, const ln_sig* sig, uint8_t* mem)
{
    for (size_t i = 0; i < sig->n; i++) {
        const sig_item* it = &sig->items[i];
        uint8_t* at = mem + it->offset;
        int rc;
        if (it->dynamic) {
            rc = dec_dynamic(c, it, at);
        } else if (it->record != NULL && it->record->has_dynamic) {
            rc = LN_OK;
            for (size_t k = 0; k < it->count && rc == LN_OK; k++) {
                push(c, it, k);
                rc = dec_record(c, it->record, at + k * it->elem_size);
                c->depth--;
            }
        } else {
            rc = dec_take(c, it, at, it->elem_size * it->count, "the data");
        }
        if (rc != LN_OK)
            return rc;
    }
    return LN_OK;
}

int ln_sig_decode(const ln_sig* sig, const uint8_t* data, size_t len, void* msg, ln_arena* arena,
                  size_t max_bytes)
{
    assert(sig != NULL && arena != NULL && (msg != NULL || sig->size == 0));
    assert(data != NULL || len == 0);
    if (len > max_bytes)
        return ln_set_error(NULL, LN_ETOOBIG, "decoding: %zu bytes exceed the limit of %zu", len,
                            max_bytes);
    if (sig->size > 0)
        memset(msg, 0, sig->size);
    codec c = {.max = max_bytes, .p = data, .left = len, .arena = arena};
    int rc = dec_record(&c, sig, msg);
    if (rc != LN_OK)
        return rc;
    if (c.left != 0)
        return ln_set_error(NULL, LN_EPROTOCOL,
                            "decoding: %zu trailing bytes after the message (%zu bytes)", c.left,
                            len - c.left);
    return LN_OK;
}
