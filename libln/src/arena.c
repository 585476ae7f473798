/* arena.c — the bump allocator of arena.h: chunks of a fixed size, larger requests in a chunk
 * of their own, 8-byte aligned blocks, everything freed or reset at once. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "arena.h"

#define ARENA_DEFAULT_CHUNK 4096

struct ln_arena_chunk {
    ln_arena_chunk* next;
    size_t size;
    size_t used;
    max_align_t data[]; /* at least 8-byte aligned */
};

void ln_arena_init(ln_arena* a, size_t chunk_size)
{
    a->head = NULL;
    a->chunk_size = chunk_size ? (chunk_size + 7) & ~(size_t)7 : ARENA_DEFAULT_CHUNK;
    a->held = 0;
}

static ln_arena_chunk* chunk_new(ln_arena* a, size_t size)
{
    if (size > SIZE_MAX - sizeof(ln_arena_chunk))
        return NULL;
    ln_arena_chunk* c = malloc(sizeof(ln_arena_chunk) + size);
    if (c == NULL)
        return NULL;
    c->next = NULL;
    c->size = size;
    c->used = 0;
    a->held += size;
    return c;
}

void* ln_arena_alloc(ln_arena* a, size_t n)
{
    if (n > SIZE_MAX - 7)
        return NULL;
    size_t need = (n + 7) & ~(size_t)7;
    ln_arena_chunk* c = a->head;
    if (c == NULL || c->size - c->used < need) {
        int own = need > a->chunk_size; /* a big block gets its own chunk */
        c = chunk_new(a, own ? need : a->chunk_size);
        if (c == NULL)
            return NULL;
        if (own && a->head != NULL) { /* behind the head, whose free space stays in use */
            c->next = a->head->next;
            a->head->next = c;
        } else {
            c->next = a->head;
            a->head = c;
        }
    }
    void* p = (uint8_t*)c->data + c->used;
    c->used += need;
    return p;
}

void ln_arena_reset(ln_arena* a)
{
    ln_arena_chunk* keep = NULL;
    ln_arena_chunk* c = a->head;
    while (c != NULL) {
        ln_arena_chunk* next = c->next;
        if (keep == NULL && c->size == a->chunk_size) {
            keep = c;
        } else {
            a->held -= c->size;
            free(c);
        }
        c = next;
    }
    if (keep != NULL) {
        keep->next = NULL;
        keep->used = 0;
    }
    a->head = keep;
}

void ln_arena_free(ln_arena* a)
{
    ln_arena_chunk* c = a->head;
    while (c != NULL) {
        ln_arena_chunk* next = c->next;
        free(c);
        c = next;
    }
    a->head = NULL;
    a->held = 0;
}

size_t ln_arena_held(const ln_arena* a) { return a->held; }
