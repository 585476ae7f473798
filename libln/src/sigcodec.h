/* sigcodec.h — the signature codec behind services: parses one section of an LN-style
 * signature (docs/message_definitions.md, "Signature") into a layout tree and converts between
 * the packed in-memory struct and a pointer-free wire form.  Internal, never installed.
 *
 * Signature grammar (exactly as ln_generate writes it, no optional spaces):
 *     section := "" | item ("," item)*
 *     item    := elem ["*"] " " SIZE " " COUNT
 *     elem    := TYPE | "[" item ("," item)* "]"
 * TYPE is char, int8_t, uint8_t, int16_t, uint16_t, int32_t, uint32_t, int64_t, uint64_t,
 * float or double; SIZE and COUNT are decimal.  SIZE is the in-memory size of ONE element (a
 * primitive's fixed size, or the sum of a record's item sizes); COUNT >= 1 is a static array
 * length.  A "*" item is a dynamic field: it has COUNT 1 and must directly follow the
 * `uint32_t 4 1` that holds its element count; together the pair occupies 4 + 8 bytes in the
 * struct (count, then a pointer to `count` packed elements).  The empty section (a service
 * with no request fields) is valid and has size 0; an empty record "[]" is not.
 *
 * Wire format (little-endian, like the packed struct on the hosts we support):
 *   - the struct is walked item by item in signature order, static array elements in order;
 *   - a fixed item (primitive, or record without dynamic fields inside) is its bytes as laid
 *     out in memory;
 *   - a record with dynamic fields inside is its items, each encoded by these rules;
 *   - a dynamic field is `u32 count` followed by `count` elements, each encoded by these
 *     rules (so records inside dynamic fields can hold dynamic fields of their own).
 * No pointers and no padding go on the wire; the decoder rejects truncation and trailing
 * bytes.
 *
 * Errors are returned as LN_E* codes and described in ln_last_error() (via ln_set_error with
 * no client): LN_EMD for a bad signature (with its column, 1-based), LN_EINVAL for a struct
 * that cannot be encoded, LN_EPROTOCOL for malformed wire data, LN_ETOOBIG for limits, and
 * LN_ENOMEM.  Items are named by their 1-based index in the signature at their level, with
 * the element index and nested item for deeper ones, e.g. "item 3[2].item 5". */
#ifndef LN_SIGCODEC_H
#define LN_SIGCODEC_H

#include <stddef.h>
#include <stdint.h>

#include "ln_internal.h"
#include "proto.h"
#include "arena.h"

/* Default for max_bytes of ln_sig_encode / ln_sig_decode. */
#define LN_SIG_DEFAULT_MAX_BYTES ((size_t)16 << 20)
/* Deepest record nesting a signature may have. */
#define LN_SIG_MAX_DEPTH 32
/* Largest in-memory struct or element size a signature may describe. */
#define LN_SIG_MAX_SIZE ((size_t)1 << 30)

/* ---- signatures -------------------------------------------------------------------------- */
typedef struct ln_sig ln_sig;

/* Parses one section (no "|") into *out, which the caller frees with ln_sig_free.
 * LN_OK, LN_EMD (text names the column and what was expected), LN_ENOMEM.  *out is NULL on
 * failure. */
int ln_sig_parse(const char* signature, ln_sig** out);
void ln_sig_free(ln_sig* sig); /* NULL is fine */
/* In-memory size of the struct the section describes (the generated `..._SIZE`). */
size_t ln_sig_size(const ln_sig* sig);

/* Splits a service or event signature "A|B" at its one "|" into two malloc'd strings the
 * caller frees with free().  LN_EMD if there is not exactly one "|", LN_ENOMEM; on failure
 * both outputs are NULL. */
int ln_sig_split(const char* signature, char** request, char** response);

/* Appends the wire form of `msg` (ln_sig_size(sig) bytes, packed as the signature says) to
 * `out`.  LN_EINVAL if a dynamic field has count > 0 and a NULL pointer; LN_ETOOBIG if the
 * appended bytes would exceed max_bytes; LN_ENOMEM (or out->failed).  On failure `out` is
 * restored to its previous length. */
int ln_sig_encode(const ln_sig* sig, const void* msg, ln_wbuf* out, size_t max_bytes);

/* Fills `msg` (ln_sig_size(sig) bytes) from exactly data[0..len).  Dynamic fields point into
 * `arena` (count 0 gives a NULL pointer; char data gets a NUL after its `count` bytes, for
 * convenience).  LN_ETOOBIG if len or the dynamic data allocated exceeds max_bytes;
 * LN_EPROTOCOL for truncation, trailing bytes, or a count that the remaining bytes cannot
 * hold (checked before allocating); LN_ENOMEM.  On failure `msg` is unspecified and whatever
 * was allocated stays in the arena until it is reset. */
int ln_sig_decode(const ln_sig* sig, const uint8_t* data, size_t len, void* msg, ln_arena* arena,
                  size_t max_bytes);

#endif /* LN_SIGCODEC_H */
