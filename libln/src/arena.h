/* arena.h — a bump allocator: many small blocks freed all at once.  Decoded service messages
 * keep their dynamic fields in one, so a request's memory is released in one step. */
#ifndef LN_ARENA_H
#define LN_ARENA_H

#include <stddef.h>

/* Bump allocator for decoded dynamic data.  Blocks are 8-byte aligned and stay valid until
 * ln_arena_reset or ln_arena_free.  The arena owns all its memory; ln_arena_free is safe on
 * an initialized or zeroed arena. */
typedef struct ln_arena_chunk ln_arena_chunk;
typedef struct ln_arena {
    ln_arena_chunk* head; /* the chunk being filled; older chunks follow */
    size_t chunk_size;    /* size of an ordinary chunk; larger requests get their own */
    size_t held;          /* bytes currently held in chunks (headers excluded) */
} ln_arena;

/* chunk_size 0 means 4096. */
void ln_arena_init(ln_arena* a, size_t chunk_size);
/* An 8-byte aligned block of n bytes (n may be 0), or NULL if out of memory. */
void* ln_arena_alloc(ln_arena* a, size_t n);
/* Invalidates every block; keeps one ordinary chunk for reuse, frees the rest. */
void ln_arena_reset(ln_arena* a);
void ln_arena_free(ln_arena* a);
/* Bytes held in chunks: lets tests see that a hostile message allocated nothing. */
size_t ln_arena_held(const ln_arena* a);

#endif /* LN_ARENA_H */
