/* fuzz_svc_secure.c — fuzz target: sealed frames of services between hosts (svc_secure.c
 * ln_svc_seal / ln_svc_open, the code a protected provider and caller run on every frame).
 * The input is a script of steps; the target seals frames itself so the fuzzer gets past the
 * tag, then alters, replays, drops or forges them and checks that only the frames sealed in
 * order open, unchanged, and everything else fails with LN_EPERM. */
#include <assert.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <sodium.h>

#include "fuzz.h"
#include "svc_secure.h"

enum { SEAL_OPEN = 0, FORGE = 1, REPLAY = 2, DROP = 3 };

/* What ln_svc_open must say about a frame sealed in order: LN_OK if it is one whole frame of a
 * type that may travel sealed. */
static int expected(const uint8_t* inner, size_t n)
{
    if (n < LN_SVC_HEADER_SIZE)
        return LN_EPROTOCOL;
    uint32_t length = (uint32_t)inner[0] | (uint32_t)inner[1] << 8 | (uint32_t)inner[2] << 16 |
                      (uint32_t)inner[3] << 24;
    uint16_t type = (uint16_t)(inner[4] | inner[5] << 8);
    return (size_t)length + 4 == n && type >= LN_SVC_HELLO && type <= LN_SVC_CALL ? LN_OK
                                                                                  : LN_EPROTOCOL;
}

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    if (size < 1 || sodium_init() < 0)
        return 0;
    ln_svc_key key = {.level = data[0] & 1 ? LN_SVC_SEC_ENCRYPT : LN_SVC_SEC_AUTHENTICATE};
    memset(key.key, 0x5a, sizeof key.key);
    int aead = (data[0] & 2) && (ln_svc_aead_offer() & LN_SVC_AEAD_AES256GCM)
                   ? LN_SVC_AEAD_AES256GCM
                   : LN_SVC_AEAD_CHACHA20;
    uint8_t nc[LN_SVC_NONCE_BYTES] = {1}, np[LN_SVC_NONCE_BYTES] = {2};
    ln_svc_channel tx, rx;
    if (ln_svc_channel_init(&tx, &key, aead, nc, np, "planner", 1) != LN_OK ||
        ln_svc_channel_init(&rx, &key, aead, nc, np, "planner", 0) != LN_OK)
        abort();
    data++;
    size--;
    ln_wbuf b, last;
    ln_wbuf_init(&b);
    ln_wbuf_init(&last);
    while (size >= 3) {
        int op = data[0];
        size_t n = (size_t)(data[1] | data[2] << 8);
        data += 3;
        size -= 3;
        if (n > size)
            n = size;
        const uint8_t* chunk = data;
        data += n;
        size -= n;
        uint16_t type;
        uint8_t* body;
        size_t body_len;
        if ((op & 3) == FORGE) { /* bytes nobody sealed */
            uint8_t* copy = malloc(n ? n : 1);
            memcpy(copy, chunk, n);
            assert(ln_svc_open(&rx, copy, n, &type, &body, &body_len) == LN_EPERM);
            free(copy);
            continue;
        }
        if ((op & 3) == REPLAY) {
            if (last.len > 0)
                assert(ln_svc_open(&rx, last.data, last.len, &type, &body, &body_len) == LN_EPERM);
            continue;
        }
        ln_wbuf_reset(&b);
        ln_wbuf_bytes(&b, chunk, n);
        assert(ln_svc_seal(&tx, &b, 0) == LN_OK);
        assert(b.len == n + LN_SVC_SEAL_OVERHEAD);
        if ((op & 3) == DROP) /* lost on the way: the receiver's counter falls behind */
            continue;
        ln_wbuf_reset(&last);
        ln_wbuf_bytes(&last, b.data, b.len);
        size_t flip = (size_t)(op >> 2);
        uint64_t seq = rx.rx_seq;
        if (flip != 0 || tx.tx_seq != rx.rx_seq + 1) { /* altered, or a frame was dropped */
            b.data[(flip * 131) % b.len] ^= (uint8_t)flip;
            assert(ln_svc_open(&rx, b.data, b.len, &type, &body, &body_len) == LN_EPERM);
            assert(rx.rx_seq == seq);
            rx.rx_seq = tx.tx_seq; /* resynchronise, as a new connection would */
            continue;
        }
        int rc = ln_svc_open(&rx, b.data, b.len, &type, &body, &body_len);
        assert(rc == expected(chunk, n));
        assert(rx.rx_seq == seq + 1);
        if (rc == LN_OK)
            assert(body_len == n - LN_SVC_HEADER_SIZE &&
                   memcmp(body, chunk + LN_SVC_HEADER_SIZE, body_len) == 0);
    }
    ln_wbuf_free(&b);
    ln_wbuf_free(&last);
    return 0;
}

/* Seeds: a HELLO and a REQUEST sealed in order at each level, then altered, replayed, dropped
 * and forged ones. */
void ln_fuzz_seeds(ln_fuzz_emit* emit)
{
    static const uint8_t hello[] = {0x0c, 0, 0, 0, 1, 0, 'L', 'N', 'S', 'V', 1, 0, 0, 0};
    static const uint8_t request[] = {0x0a, 0, 0, 0, 3, 0, 1, 0, 0, 0, 'a', 'b', 'c', 'd'};
    uint8_t in[128];
    for (int level = 0; level < 4; level++) {
        size_t n = 0;
        in[n++] = (uint8_t)level;
        const uint8_t ops[] = {SEAL_OPEN, SEAL_OPEN, REPLAY, SEAL_OPEN | 4 << 2,
                               DROP,      SEAL_OPEN, FORGE};
        for (size_t i = 0; i < sizeof ops; i++) {
            const uint8_t* frame = i == 0 ? hello : request;
            in[n++] = ops[i];
            in[n++] = sizeof request;
            in[n++] = 0;
            memcpy(in + n, frame, sizeof request);
            n += sizeof request;
        }
        char name[32];
        snprintf(name, sizeof name, "script_level%d", level);
        emit(name, in, n);
    }
}
