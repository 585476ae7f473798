/* ndn_content.c — the Content of pull-topic Data: header TLVs (0x80 latest seq, 0x82 publish
 * time µs, 0x84 mean period µs) then 0x86 with the sample's bytes (absent in a NACK). */
#include <string.h>

#include "ndn_internal.h"

LN_NDN_EXPORT int ln_ndn_encode_pull_content(uint8_t* out, size_t cap, const ln_ndn_pull_content* c)
{
    size_t p = 0, need;
    if (!c || (!out && cap) || (!c->payload.data && c->payload.size))
        return LN_NDN_EINVAL;
    cap = LN_NDN_I_CLAMP(cap);
    need = 2 + ln_ndn_i_nonneg_size(c->latest_seq) +
           (c->publish_us ? 2 + ln_ndn_i_nonneg_size(c->publish_us) : 0) +
           (c->period_us ? 2 + ln_ndn_i_nonneg_size(c->period_us) : 0);
    if (c->payload.data) {
        if (c->payload.size > cap)
            return LN_NDN_ESPACE;
        need += ln_ndn_i_tlv_size(LN_NDN_T_PULL_PAYLOAD, c->payload.size);
    }
    if (need > cap)
        return LN_NDN_ESPACE;
    /* the payload first: it may already sit where it goes */
    if (c->payload.data && c->payload.size)
        memmove(out + need - c->payload.size, c->payload.data, c->payload.size);
    p += ln_ndn_i_put_header(out, LN_NDN_T_PULL_LATEST, ln_ndn_i_nonneg_size(c->latest_seq));
    p += ln_ndn_i_put_nonneg(out + p, c->latest_seq);
    if (c->publish_us) {
        p += ln_ndn_i_put_header(out + p, LN_NDN_T_PULL_TIME, ln_ndn_i_nonneg_size(c->publish_us));
        p += ln_ndn_i_put_nonneg(out + p, c->publish_us);
    }
    if (c->period_us) {
        p += ln_ndn_i_put_header(out + p, LN_NDN_T_PULL_PERIOD, ln_ndn_i_nonneg_size(c->period_us));
        p += ln_ndn_i_put_nonneg(out + p, c->period_us);
    }
    if (c->payload.data)
        ln_ndn_i_put_header(out + p, LN_NDN_T_PULL_PAYLOAD, c->payload.size);
    return (int)need;
}

LN_NDN_EXPORT int ln_ndn_decode_pull_content(ln_ndn_bytes content, ln_ndn_pull_content* out)
{
    static const uint8_t order[] = {LN_NDN_T_PULL_LATEST, LN_NDN_T_PULL_TIME, LN_NDN_T_PULL_PERIOD,
                                    LN_NDN_T_PULL_PAYLOAD};
    ln_ndn_i_tlv t;
    size_t next = 0, i;
    int r;
    if (!out || (!content.data && content.size))
        return LN_NDN_EINVAL;
    memset(out, 0, sizeof *out);
    while ((r = ln_ndn_i_next(&content, &t)) > 0) {
        for (i = next; i < 4 && order[i] != t.type; i++) {
        }
        if (i == 4) { /* unknown or out of order */
            if (ln_ndn_i_critical(t.type)) {
                memset(out, 0, sizeof *out);
                return LN_NDN_ECRITICAL;
            }
            continue;
        }
        next = i + 1;
        if (i == 3) {
            out->payload = t.value;
            if (!out->payload.data) /* never happens: value points into content */
                out->payload.data = t.start;
            continue;
        }
        r = ln_ndn_read_nonneg(t.value, i == 0   ? &out->latest_seq
                                        : i == 1 ? &out->publish_us
                                                 : &out->period_us);
        if (r < 0) {
            memset(out, 0, sizeof *out);
            return r;
        }
    }
    if (r < 0)
        memset(out, 0, sizeof *out);
    return r < 0 ? r : LN_NDN_OK;
}
