/* fuzz_sigcodec.c — fuzz target: the signature codec (libln/src/sigcodec.c): wire data decoded
 * against a signature from the tests (nested records, dynamic arrays) or one of the input's
 * own; whatever decodes must encode back to the very same bytes. */
#include <assert.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz.h"
#include "sigcodec.h"

#define MAX_BYTES ((size_t)1 << 16)
/* the records of lntest/inner, middle and outer, each without its " SIZE COUNT" */
#define INNER "[int16_t 2 1,float 4 2,char 1 4]"
#define MIDDLE "[uint8_t 1 1," INNER " 14 1," INNER " 14 3,uint32_t 4 1," INNER "* 14 1]"
#define OUTER                                                                                      \
    "[[int64_t 8 1,uint32_t 4 1] 12 1," MIDDLE " 69 1," MIDDLE " 69 2,"                            \
    "[double 8 3,double 8 4] 56 1,uint32_t 4 1," MIDDLE "* 69 1,uint32_t 4 1,"                     \
    "char* 1 1,double 8 1]"

static const char* const signatures[] = {
    "", /* a request without fields */
    "uint32_t 4 1,char* 1 1",
    /* robot/plan_path request and response */
    "double 8 7,double 8 1,uint32_t 4 1,[uint32_t 4 1,char* 1 1]* 12 1",
    "uint32_t 4 1,[double 8 1,uint32_t 4 1,double 8 7,double 8 7,double 8 7]* 180 1,"
    "int32_t 4 1,uint32_t 4 1,char* 1 1",
    /* lntest/query request, lntest/outer, lntest/deep */
    "uint32_t 4 1," MIDDLE "* 69 1,uint32_t 4 1,[uint32_t 4 1,char* 1 1]* 12 1,uint8_t 1 1",
    OUTER " 307 1",
    OUTER " 307 2,uint32_t 4 1," OUTER "* 307 1," INNER " 14 1",
    "char 1 1,int8_t 1 1,uint8_t 1 1,int16_t 2 1,uint16_t 2 1,int32_t 4 1,uint32_t 4 1,"
    "int64_t 8 1,uint64_t 8 1,float 4 1,double 8 1,char 1 16,uint16_t 2 2,double 8 3",
};
#define NSIG (sizeof signatures / sizeof signatures[0])

static void roundtrip(const ln_sig* sig, const uint8_t* data, size_t size)
{
    size_t msg_size = ln_sig_size(sig);
    if (msg_size > ((size_t)1 << 20))
        return; /* a hostile signature may describe a huge struct: not the decoder's problem */
    uint8_t* msg = malloc(msg_size ? msg_size : 1);
    if (msg == NULL)
        return;
    ln_arena arena;
    ln_arena_init(&arena, 0);
    if (ln_sig_decode(sig, data, size, msg, &arena, MAX_BYTES) == LN_OK) {
        ln_wbuf out;
        ln_wbuf_init(&out);
        int rc = ln_sig_encode(sig, msg, &out, MAX_BYTES);
        assert(rc == LN_OK && out.len == size && (size == 0 || memcmp(out.data, data, size) == 0));
        (void)rc;
        ln_wbuf_free(&out);
    }
    ln_arena_free(&arena);
    free(msg);
}

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    if (size < 1)
        return 0;
    unsigned pick = data[0] % (NSIG + 1);
    data++;
    size--;
    ln_sig* sig = NULL;
    if (pick < NSIG) {
        if (ln_sig_parse(signatures[pick], &sig) != LN_OK)
            abort(); /* the fixed signatures are valid */
    } else {
        /* "SIGNATURE\0WIRE": the signature text is hostile as well */
        const uint8_t* nul = memchr(data, '\0', size);
        size_t n = nul ? (size_t)(nul - data) : size;
        char* text = malloc(n + 1);
        if (text == NULL)
            return 0;
        memcpy(text, data, n);
        text[n] = '\0';
        int rc = ln_sig_parse(text, &sig);
        assert((rc == LN_OK) == (sig != NULL));
        free(text);
        data += nul ? n + 1 : n;
        size -= nul ? n + 1 : n;
        if (sig == NULL)
            return 0;
    }
    roundtrip(sig, data, size);
    ln_sig_free(sig);
    return 0;
}

/* ---- seeds: messages encoded by ln_sig_encode --------------------------------------------- */

static void put_u32(uint8_t* p, uint32_t v)
{
    memcpy(p, &v, 4); /* the packed structs are little-endian, like the wire */
}

static void put_ptr(uint8_t* p, const void* v) { memcpy(p, &v, sizeof v); }

static void emit_encoded(ln_fuzz_emit* emit, const char* name, unsigned pick, const void* msg)
{
    ln_sig* sig = NULL;
    if (ln_sig_parse(signatures[pick], &sig) != LN_OK)
        return;
    ln_wbuf b;
    ln_wbuf_init(&b);
    uint8_t tag = (uint8_t)pick;
    ln_wbuf_bytes(&b, &tag, 1);
    if (ln_sig_encode(sig, msg, &b, MAX_BYTES) == LN_OK)
        emit(name, b.data, b.len);
    ln_wbuf_free(&b);
    ln_sig_free(sig);
}

void ln_fuzz_seeds(ln_fuzz_emit* emit)
{
    for (unsigned i = 0; i < NSIG; i++) { /* one seed per signature: the all-zero message */
        ln_sig* sig;
        if (ln_sig_parse(signatures[i], &sig) != LN_OK)
            abort();
        uint8_t* zero = calloc(1, ln_sig_size(sig) + 1);
        char name[32];
        snprintf(name, sizeof name, "zero_%u", i);
        if (zero != NULL)
            emit_encoded(emit, name, i, zero);
        free(zero);
        ln_sig_free(sig);
    }
    /* uint32_t 4 1,char* 1 1 */
    uint8_t str[12];
    const char* hello = "hello";
    put_u32(str, 5);
    put_ptr(str + 4, hello);
    emit_encoded(emit, "string", 1, str);

    /* plan_path request: 7+1 doubles, then two {u32, char*} waypoints */
    uint8_t wp[2][12];
    const char* names[2] = {"home", "tool"};
    for (int i = 0; i < 2; i++) {
        put_u32(wp[i], (uint32_t)strlen(names[i]));
        put_ptr(wp[i] + 4, names[i]);
    }
    uint8_t req[8 * 8 + 4 + 8];
    for (int i = 0; i < 8; i++) {
        double d = 0.5 * i;
        memcpy(req + 8 * i, &d, 8);
    }
    put_u32(req + 64, 2);
    put_ptr(req + 68, wp);
    emit_encoded(emit, "plan_path_request", 2, req);

    /* lntest/query request: one middle record with one inner record in its dynamic field */
    uint8_t inner[14] = {1, 0, 0, 0, 0x80, 0x3f, 0, 0, 0, 0x40, 'a', 'b', 'c', 'd'};
    uint8_t middle[69];
    memset(middle, 0x11, sizeof middle);
    put_u32(middle + 57, 1);
    put_ptr(middle + 61, inner);
    uint8_t query[4 + 8 + 4 + 8 + 1]; /* count, middle*, count, waypoints*, u8 */
    put_u32(query, 1);
    put_ptr(query + 4, middle);
    put_u32(query + 12, 2);
    put_ptr(query + 16, wp);
    query[24] = 1;
    emit_encoded(emit, "query_request", 4, query);

    /* a signature of its own, then its wire data */
    static const uint8_t own[] = "\x08uint32_t 4 1,[uint32_t 4 1,char* 1 1]* 12 1,uint16_t 2 2\0"
                                 "\x01\x00\x00\x00\x02\x00\x00\x00hi\x05\x00\x06\x00";
    emit("own_signature", own, sizeof own - 1);
}
