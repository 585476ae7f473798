/* ndn_internal.h — helpers shared by the codec's files (not installed): VAR-NUMBER and
 * NonNegativeInteger sizes and writers, a bounds-checked TLV reader and the evolvability
 * rule.  Everything here is hidden (the build uses -fvisibility=hidden). */
#ifndef LN_NDN_INTERNAL_H
#define LN_NDN_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "ln/ndn.h"

/* Encoders handle sizes below 2^31 only (so 32-bit arithmetic is enough, which keeps the code
 * small on small cores): each clamps its capacity to this first. */
#define LN_NDN_I_MAX 0x7fffffffu
#define LN_NDN_I_CLAMP(cap) ((cap) > LN_NDN_I_MAX ? LN_NDN_I_MAX : (cap))

/* Bytes of a VAR-NUMBER (of a type or length) / of a NonNegativeInteger's value. */
static inline size_t ln_ndn_i_varnum_size(uint32_t v) { return v < 253 ? 1 : v <= 0xffffu ? 3 : 5; }
static inline size_t ln_ndn_i_nonneg_size(uint64_t v)
{
    return v <= 0xffu ? 1 : v <= 0xffffu ? 2 : v <= 0xffffffffu ? 4 : 8;
}
/* Bytes of a whole TLV with a value of `size` bytes. */
static inline size_t ln_ndn_i_tlv_size(uint32_t type, size_t size)
{
    return ln_ndn_i_varnum_size(type) + ln_ndn_i_varnum_size((uint32_t)size) + size;
}
/* Writers with no bounds check (the caller measured first); they return the bytes written. */
size_t ln_ndn_i_put_varnum(uint8_t* p, uint32_t v);
size_t ln_ndn_i_put_nonneg(uint8_t* p, uint64_t v);
size_t ln_ndn_i_put_header(uint8_t* p, uint32_t type, size_t size);

/* One TLV element taken off the front of *rest: 1, 0 at the end, or an error. */
typedef struct ln_ndn_i_tlv {
    uint64_t type;
    ln_ndn_bytes value;
    const uint8_t* start; /* the element's first byte */
    size_t size;          /* the whole element's size */
} ln_ndn_i_tlv;
int ln_ndn_i_next(ln_ndn_bytes* rest, ln_ndn_i_tlv* out);

/* The evolvability rule of packet format 0.3: an unknown (or out-of-order) element is
 * critical if its type is below 32 or odd. */
static inline int ln_ndn_i_critical(uint64_t type) { return type < 32 || (type & 1u); }

#endif
