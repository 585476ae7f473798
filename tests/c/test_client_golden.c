/* test_client_golden.c — libln's generated client <-> manager codec (client_wire.c, from
 * python/links_and_nodes/wire/client.schema) against the golden frames of
 * tests/wire/client_golden.txt, which the manager's Python codec must produce too: every
 * message of libln's table encodes to exactly its frame and decodes back to its fields. */
#include <stdalign.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ln_test.h"
#include "proto.h"

#define MAX_LINE 4096

struct vector {
    int line; /* of the `TYPE field=value ...` line */
    char spec[MAX_LINE];
    uint8_t frame[MAX_LINE];
    size_t frame_len;
};

static int hex_digit(int c)
{
    if (c >= '0' && c <= '9')
        return c - '0';
    if (c >= 'a' && c <= 'f')
        return c - 'a' + 10;
    if (c >= 'A' && c <= 'F')
        return c - 'A' + 10;
    return -1;
}

/* Appends the hex digits of `line` to v->frame; 0 on a stray character. */
static int add_hex(struct vector* v, const char* line)
{
    int high = -1;
    for (const char* p = line; *p != '\0' && *p != '\n'; p++) {
        if (*p == ' ' || *p == '\t')
            continue;
        int d = hex_digit((unsigned char)*p);
        if (d < 0 || v->frame_len >= sizeof v->frame)
            return 0;
        if (high < 0) {
            high = d;
        } else {
            v->frame[v->frame_len++] = (uint8_t)(high << 4 | d);
            high = -1;
        }
    }
    return high < 0;
}

/* Reads the next vector; 1 if there was one, 0 at the end. */
static int next_vector(FILE* f, int* lineno, struct vector* v, char* pending, int* has_pending)
{
    char line[MAX_LINE];
    memset(v, 0, sizeof *v);
    for (;;) {
        if (*has_pending) {
            memcpy(line, pending, sizeof line);
            *has_pending = 0;
        } else if (fgets(line, sizeof line, f) == NULL) {
            return v->line != 0;
        } else {
            ++*lineno;
        }
        if (line[0] == '#' || line[0] == '\n')
            continue;
        if (line[0] == ' ') {
            LN_CHECK(v->line != 0 && add_hex(v, line));
            continue;
        }
        if (v->line != 0) { /* the start of the next vector */
            memcpy(pending, line, sizeof line);
            *has_pending = 1;
            return 1;
        }
        line[strcspn(line, "\n")] = '\0';
        memcpy(v->spec, line, sizeof v->spec);
        v->line = *lineno;
    }
}

/* The next token of *p: a word up to a space, with "..." parts unescaped into out (the
 * quoted flag says whether it was a string).  0 at the end of the line. */
static int next_token(const char** p, char* out, size_t* len, int* quoted)
{
    const char* s = *p;
    while (*s == ' ')
        s++;
    if (*s == '\0')
        return 0;
    *len = 0;
    *quoted = 0;
    while (*s != '\0' && *s != ' ') {
        if (*s != '"') {
            out[(*len)++] = *s++;
            continue;
        }
        *quoted = 1;
        for (s++; *s != '"' && *s != '\0'; s++) {
            if (*s == '\\' && s[1] == 'x') {
                out[(*len)++] =
                    (char)(hex_digit((unsigned char)s[2]) << 4 | hex_digit((unsigned char)s[3]));
                s += 3;
            } else {
                if (*s == '\\')
                    s++;
                out[(*len)++] = *s;
            }
        }
        if (*s == '"')
            s++;
    }
    out[*len] = '\0';
    *p = s;
    return 1;
}

static const ln_wire_msg_info* find_msg(const char* name)
{
    for (size_t i = 0; i < ln_client_wire_msg_count; i++)
        if (strcmp(ln_client_wire_msgs[i].name, name) == 0)
            return &ln_client_wire_msgs[i];
    return NULL;
}

/* Fills the struct at `m` from the field=value tokens of `spec`, strings into `pool`. */
static int fill(const ln_wire_msg_info* info, const char* spec, unsigned char* m, char* pool)
{
    size_t used = 0, k = 0, len;
    int quoted;
    char token[MAX_LINE];
    while (next_token(&spec, token, &len, &quoted)) {
        char* eq = strchr(token, '=');
        if (eq == NULL || k >= info->field_count)
            return 0;
        const ln_wire_field* f = &info->fields[k++];
        if ((size_t)(eq - token) != strlen(f->name) || strncmp(token, f->name, strlen(f->name)))
            return 0; /* every field, in schema order */
        const char* value = eq + 1;
        size_t vlen = len - (size_t)(value - token);
        unsigned char* at = m + f->offset;
        if (f->kind == 's' || f->kind == 't') {
            if (!quoted)
                return 0;
            memcpy(pool + used, value, vlen);
            ln_strv v = {pool + used, vlen};
            memcpy(at, &v, sizeof v);
            used += vlen + 1;
            continue;
        }
        long long n = strtoll(value, NULL, 0);
        unsigned long long u = strtoull(value, NULL, 0);
        switch (f->kind) {
        case 'w':
            *(uint16_t*)(void*)at = (uint16_t)u;
            break;
        case 'd':
            *(uint32_t*)(void*)at = (uint32_t)u;
            break;
        case 'q':
            *(uint64_t*)(void*)at = (uint64_t)u;
            break;
        case 'i':
            *(int32_t*)(void*)at = (int32_t)n;
            break;
        default:
            return 0;
        }
    }
    return k == info->field_count;
}

/* Field-by-field equality of two structs of message `info`. */
static int same(const ln_wire_msg_info* info, const unsigned char* a, const unsigned char* b)
{
    for (size_t k = 0; k < info->field_count; k++) {
        const ln_wire_field* f = &info->fields[k];
        if (f->kind == 's' || f->kind == 't') {
            ln_strv x, y;
            memcpy(&x, a + f->offset, sizeof x);
            memcpy(&y, b + f->offset, sizeof y);
            if (x.len != y.len || (x.len > 0 && memcmp(x.s, y.s, x.len) != 0))
                return 0;
            continue;
        }
        size_t size = f->kind == 'w' ? 2 : f->kind == 'q' ? 8 : 4;
        if (memcmp(a + f->offset, b + f->offset, size) != 0)
            return 0;
    }
    return 1;
}

static void test_golden_frames(void)
{
    FILE* f = fopen(LN_GOLDEN_FILE, "r");
    LN_CHECK(f != NULL);
    if (f == NULL)
        return;
    static struct vector v;
    static char pending[MAX_LINE], pool[MAX_LINE];
    int lineno = 0, has_pending = 0, vectors = 0;
    int covered[64] = {0};
    LN_CHECK(ln_client_wire_msg_count <= 64);
    while (next_vector(f, &lineno, &v, pending, &has_pending)) {
        char name[64];
        size_t n = strcspn(v.spec, " ");
        snprintf(name, sizeof name, "%.*s", (int)n, v.spec);
        const ln_wire_msg_info* info = find_msg(name);
        if (info == NULL) /* a message libln leaves out (LIST_SERVICES, SERVICE_LIST) */
            continue;
        vectors++;
        covered[info - ln_client_wire_msgs] = 1;
        alignas(max_align_t) unsigned char want[512], got[512];
        LN_CHECK(info->size <= sizeof want);
        memset(want, 0, sizeof want);
        memset(got, 0, sizeof got);
        int filled = fill(info, v.spec + n, want, pool);
        if (!filled)
            fprintf(stderr, "golden line %d: fields do not match %s\n", v.line, name);
        LN_CHECK(filled);

        ln_wbuf b; /* encoding gives exactly the golden frame */
        ln_wbuf_init(&b);
        size_t start = ln_proto_frame_begin(&b, info->type);
        info->write(&b, want);
        LN_CHECK_EQ(ln_proto_frame_end(&b, start), LN_OK);
        int equal = b.len == v.frame_len && memcmp(b.data, v.frame, b.len) == 0;
        if (!equal)
            fprintf(stderr, "golden line %d: %s encodes to other bytes\n", v.line, name);
        LN_CHECK(equal);
        ln_wbuf_free(&b);

        uint16_t type = 0; /* and the golden frame decodes to the same fields */
        ln_rbuf body;
        LN_CHECK_EQ(ln_proto_decode_frame(v.frame, v.frame_len, &type, &body), LN_OK);
        LN_CHECK_EQ(type, info->type);
        LN_CHECK_EQ(ln_proto_check_fields(type, &body), LN_OK);
        LN_CHECK_EQ(info->read(&body, got), LN_OK);
        int decoded = same(info, want, got);
        if (!decoded)
            fprintf(stderr, "golden line %d: %s decodes to other fields\n", v.line, name);
        LN_CHECK(decoded);
    }
    fclose(f);
    LN_CHECK(vectors >= (int)ln_client_wire_msg_count);
    for (size_t i = 0; i < ln_client_wire_msg_count; i++) {
        if (!covered[i])
            fprintf(stderr, "no golden frame of %s\n", ln_client_wire_msgs[i].name);
        LN_CHECK(covered[i]);
    }
}

int main(void)
{
    LN_TEST_RUN(test_golden_frames);
    LN_TEST_EXIT();
}
