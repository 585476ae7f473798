/* mex_layout.h — the run-time layout of one md section for the MEX gateway: parsed from the
 * signature ln_generate writes (libln/src/sigcodec.h has the grammar) and the field names the
 * manager's `md_layout` answer lists in pre-order (docs/matlab.md).  Plain C, no MEX calls. */
#ifndef LN_MEX_LAYOUT_H
#define LN_MEX_LAYOUT_H

#include <stddef.h>
#include <stdint.h>

typedef enum lnm_type {
    LNM_CHAR,
    LNM_INT8,
    LNM_UINT8,
    LNM_INT16,
    LNM_UINT16,
    LNM_INT32,
    LNM_UINT32,
    LNM_INT64,
    LNM_UINT64,
    LNM_FLOAT,
    LNM_DOUBLE,
    LNM_RECORD
} lnm_type;

/* A dynamic field occupies LNM_DYNAMIC_SIZE bytes: uint32 count, then a pointer. */
#define LNM_DYNAMIC_SIZE 12u

typedef struct lnm_node {
    lnm_type type;
    int dynamic;             /* a `*` field: count + pointer to `count` packed elements */
    uint32_t count;          /* static element count (1 for a dynamic field) */
    size_t elem_size;        /* in-memory size of one element */
    size_t offset;           /* from the start of the enclosing record */
    char* name;              /* NULL for the section itself */
    struct lnm_node* fields; /* a record's fields */
    size_t nfields;
    const char** field_names; /* the fields' names, for mxCreateStructMatrix */
} lnm_node;

/* Parses section `signature` with its pre-order `names` ("a,b,c") into *out (a record whose
 * elem_size is the struct size).  0 on success, else -1 with a message in err[size]. */
int lnm_layout_parse(const char* signature, const char* names, lnm_node** out, char* err,
                     size_t err_size);
void lnm_layout_free(lnm_node* node); /* NULL is fine */
/* 1 if the record holds a dynamic field at any depth. */
int lnm_layout_has_dynamic(const lnm_node* node);
/* The md primitive name of a type ("int32_t", "double", ...; "record"). */
const char* lnm_type_name(lnm_type type);
/* Size in bytes of a primitive type (0 for LNM_RECORD). */
size_t lnm_type_size(lnm_type type);

#endif /* LN_MEX_LAYOUT_H */
