/* mex_layout.c — parses one section of an md signature plus its pre-order field names into
 * the node tree the MEX gateway packs and unpacks samples with (mex_layout.h). */
#include "mex_layout.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const struct {
    const char* name;
    lnm_type type;
    size_t size;
} PRIMS[] = {
    {"char", LNM_CHAR, 1},       {"int8_t", LNM_INT8, 1},     {"uint8_t", LNM_UINT8, 1},
    {"int16_t", LNM_INT16, 2},   {"uint16_t", LNM_UINT16, 2}, {"int32_t", LNM_INT32, 4},
    {"uint32_t", LNM_UINT32, 4}, {"int64_t", LNM_INT64, 8},   {"uint64_t", LNM_UINT64, 8},
    {"float", LNM_FLOAT, 4},     {"double", LNM_DOUBLE, 8},
};
#define NPRIMS (sizeof PRIMS / sizeof PRIMS[0])
#define MAX_DEPTH 32

typedef struct parser {
    const char* sig;
    const char* p;
    char* err;
    size_t err_size;
} parser;

const char* lnm_type_name(lnm_type type)
{
    for (size_t i = 0; i < NPRIMS; i++)
        if (PRIMS[i].type == type)
            return PRIMS[i].name;
    return "record";
}

size_t lnm_type_size(lnm_type type)
{
    for (size_t i = 0; i < NPRIMS; i++)
        if (PRIMS[i].type == type)
            return PRIMS[i].size;
    return 0;
}

static int fail(parser* ps, const char* fmt, ...)
{
    char what[160];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    snprintf(ps->err, ps->err_size, "bad signature at column %d: %s", (int)(ps->p - ps->sig) + 1,
             what);
    return -1;
}

static void free_fields(lnm_node* node)
{
    for (size_t i = 0; i < node->nfields; i++) {
        free_fields(&node->fields[i]);
        free(node->fields[i].name);
    }
    free(node->fields);
    free(node->field_names);
    node->fields = NULL;
    node->field_names = NULL;
    node->nfields = 0;
}

void lnm_layout_free(lnm_node* node)
{
    if (node == NULL)
        return;
    free_fields(node);
    free(node);
}

static int parse_number(parser* ps, size_t* out)
{
    if (*ps->p < '0' || *ps->p > '9')
        return fail(ps, "expected a number");
    size_t v = 0;
    while (*ps->p >= '0' && *ps->p <= '9') {
        v = v * 10 + (size_t)(*ps->p - '0');
        if (v > ((size_t)1 << 30))
            return fail(ps, "number too large");
        ps->p++;
    }
    *out = v;
    return 0;
}

static int parse_items(parser* ps, lnm_node* rec, int depth);

static int parse_elem(parser* ps, lnm_node* item, int depth)
{
    if (*ps->p == '[') {
        if (depth >= MAX_DEPTH)
            return fail(ps, "nested deeper than %d", MAX_DEPTH);
        ps->p++;
        item->type = LNM_RECORD;
        if (parse_items(ps, item, depth + 1) < 0)
            return -1;
        if (*ps->p != ']')
            return fail(ps, "expected ']'");
        ps->p++;
        return 0;
    }
    size_t len = strspn(ps->p, "abcdefghijklmnopqrstuvwxyz0123456789_");
    for (size_t i = 0; i < NPRIMS; i++) {
        if (strlen(PRIMS[i].name) == len && strncmp(PRIMS[i].name, ps->p, len) == 0) {
            item->type = PRIMS[i].type;
            ps->p += len;
            return 0;
        }
    }
    return fail(ps, "expected a primitive type or '['");
}

static int parse_item(parser* ps, lnm_node* item, int depth)
{
    if (parse_elem(ps, item, depth) < 0)
        return -1;
    if (*ps->p == '*') {
        item->dynamic = 1;
        ps->p++;
    }
    size_t size = 0, count = 0;
    if (*ps->p++ != ' ' || parse_number(ps, &size) < 0)
        return fail(ps, "expected ' SIZE'");
    if (*ps->p++ != ' ' || parse_number(ps, &count) < 0)
        return fail(ps, "expected ' COUNT'");
    size_t expect = item->type == LNM_RECORD ? item->elem_size : lnm_type_size(item->type);
    if (size != expect)
        return fail(ps, "element size %zu, expected %zu", size, expect);
    if (count < 1 || (item->dynamic && count != 1))
        return fail(ps, "bad count %zu", count);
    item->elem_size = size;
    item->count = (uint32_t)count;
    return 0;
}

/* Appends the items up to ']' or the end to rec->fields, merging each `uint32_t 4 1` with the
 * dynamic item after it, and sets the offsets and rec->elem_size. */
static int parse_items(parser* ps, lnm_node* rec, int depth)
{
    size_t cap = 0, offset = 0;
    if (*ps->p == '\0' && depth == 0)
        return 0; /* the empty section */
    for (;;) {
        if (rec->nfields == cap) {
            cap = cap ? cap * 2 : 8;
            lnm_node* grown = realloc(rec->fields, cap * sizeof *grown);
            if (grown == NULL)
                return fail(ps, "out of memory");
            rec->fields = grown;
        }
        lnm_node* item = &rec->fields[rec->nfields];
        memset(item, 0, sizeof *item);
        rec->nfields++;
        if (parse_item(ps, item, depth) < 0)
            return -1;
        if (item->dynamic) {
            lnm_node* len = rec->nfields >= 2 ? &rec->fields[rec->nfields - 2] : NULL;
            if (len == NULL || len->type != LNM_UINT32 || len->dynamic || len->count != 1)
                return fail(ps, "a dynamic item must follow its 'uint32_t 4 1' count");
            offset = len->offset;
            *len = *item;
            rec->nfields--;
            item = len;
        }
        item->offset = offset;
        offset += item->dynamic ? LNM_DYNAMIC_SIZE : item->elem_size * item->count;
        if (*ps->p != ',')
            break;
        ps->p++;
    }
    rec->elem_size = offset;
    return 0;
}

/* Gives every field its name from the comma-separated list at *names, in pre-order. */
static int assign_names(lnm_node* rec, const char** names, char* err, size_t err_size)
{
    rec->field_names = calloc(rec->nfields ? rec->nfields : 1, sizeof *rec->field_names);
    if (rec->field_names == NULL)
        return -1;
    for (size_t i = 0; i < rec->nfields; i++) {
        const char* start = *names;
        size_t len = strcspn(start, ",");
        if (len == 0) {
            snprintf(err, err_size, "the layout names fewer fields than its signature has");
            return -1;
        }
        lnm_node* f = &rec->fields[i];
        f->name = malloc(len + 1);
        if (f->name == NULL)
            return -1;
        memcpy(f->name, start, len);
        f->name[len] = '\0';
        rec->field_names[i] = f->name;
        *names = start[len] == ',' ? start + len + 1 : start + len;
        if (f->type == LNM_RECORD && assign_names(f, names, err, err_size) < 0)
            return -1;
    }
    return 0;
}

int lnm_layout_parse(const char* signature, const char* names, lnm_node** out, char* err,
                     size_t err_size)
{
    *out = NULL;
    lnm_node* root = calloc(1, sizeof *root);
    if (root == NULL) {
        snprintf(err, err_size, "out of memory");
        return -1;
    }
    root->type = LNM_RECORD;
    root->count = 1;
    parser ps = {signature, signature, err, err_size};
    if (parse_items(&ps, root, 0) < 0)
        goto failed;
    if (*ps.p != '\0') {
        fail(&ps, "unexpected text after the last item");
        goto failed;
    }
    snprintf(err, err_size, "out of memory");
    if (assign_names(root, &names, err, err_size) < 0)
        goto failed;
    if (*names != '\0') {
        snprintf(err, err_size, "the layout names more fields than its signature has");
        goto failed;
    }
    *out = root;
    return 0;
failed:
    lnm_layout_free(root);
    return -1;
}

int lnm_layout_has_dynamic(const lnm_node* node)
{
    for (size_t i = 0; i < node->nfields; i++) {
        const lnm_node* f = &node->fields[i];
        if (f->dynamic || (f->type == LNM_RECORD && lnm_layout_has_dynamic(f)))
            return 1;
    }
    return 0;
}
