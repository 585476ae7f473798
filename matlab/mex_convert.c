/* mex_convert.c — packs MATLAB/Octave structs into md structs and unpacks them: numbers as
 * row vectors of the md type's class, char fields as char, nested mds as (arrays of) structs,
 * dynamic fields with the length of the value (docs/matlab.md, "Type mapping"). */
#include "mex_convert.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define PATH_MAX_LEN 512

static mxClassID class_of(lnm_type t)
{
    switch (t) {
    case LNM_CHAR:
        return mxCHAR_CLASS;
    case LNM_INT8:
        return mxINT8_CLASS;
    case LNM_UINT8:
        return mxUINT8_CLASS;
    case LNM_INT16:
        return mxINT16_CLASS;
    case LNM_UINT16:
        return mxUINT16_CLASS;
    case LNM_INT32:
        return mxINT32_CLASS;
    case LNM_UINT32:
        return mxUINT32_CLASS;
    case LNM_INT64:
        return mxINT64_CLASS;
    case LNM_UINT64:
        return mxUINT64_CLASS;
    case LNM_FLOAT:
        return mxSINGLE_CLASS;
    case LNM_DOUBLE:
        return mxDOUBLE_CLASS;
    case LNM_RECORD:
        return mxSTRUCT_CLASS;
    }
    return mxUNKNOWN_CLASS;
}

static void field_error(const char* path, const char* fmt, const char* a, double b)
{
    char what[256];
    snprintf(what, sizeof what, fmt, a, b);
    mexErrMsgIdAndTxt("ln:field", "%s: %s", path, what);
}

/* The declared type of a field for messages: "double[7]", "int32_t", "char*", "record[2]". */
static const char* declared(const lnm_node* f, char* buf, size_t size)
{
    const char* t = lnm_type_name(f->type);
    if (f->dynamic)
        snprintf(buf, size, "%s*", t);
    else if (f->count > 1)
        snprintf(buf, size, "%s[%u]", t, (unsigned)f->count);
    else
        snprintf(buf, size, "%s", t);
    return buf;
}

static double element_double(const mxArray* v, size_t i)
{
    const void* d = mxGetData(v);
    switch (mxGetClassID(v)) {
    case mxDOUBLE_CLASS:
        return ((const double*)d)[i];
    case mxSINGLE_CLASS:
        return ((const float*)d)[i];
    case mxINT8_CLASS:
        return ((const int8_t*)d)[i];
    case mxUINT8_CLASS:
        return ((const uint8_t*)d)[i];
    case mxINT16_CLASS:
        return ((const int16_t*)d)[i];
    case mxUINT16_CLASS:
        return ((const uint16_t*)d)[i];
    case mxINT32_CLASS:
        return ((const int32_t*)d)[i];
    case mxUINT32_CLASS:
        return ((const uint32_t*)d)[i];
    case mxINT64_CLASS:
        return (double)((const int64_t*)d)[i];
    case mxUINT64_CLASS:
        return (double)((const uint64_t*)d)[i];
    case mxLOGICAL_CLASS:
        return ((const mxLogical*)d)[i] ? 1.0 : 0.0;
    default:
        return NAN;
    }
}

/* Stores element i of numeric `v` as type t at dst: the same class is copied bit for bit;
 * another one must hold an integral value in range for an integer type. */
static void store_number(const lnm_node* f, void* dst, const mxArray* v, size_t i, const char* path)
{
    size_t size = lnm_type_size(f->type);
    if (mxGetClassID(v) == class_of(f->type)) {
        memcpy(dst, (const char*)mxGetData(v) + i * size, size);
        return;
    }
    double d = element_double(v, i);
    if (f->type == LNM_DOUBLE) {
        memcpy(dst, &d, 8);
        return;
    }
    if (f->type == LNM_FLOAT) {
        float x = (float)d;
        memcpy(dst, &x, 4);
        return;
    }
    char elem[PATH_MAX_LEN + 32];
    if (f->count > 1 || f->dynamic)
        snprintf(elem, sizeof elem, "%s(%zu)", path, i + 1);
    else
        snprintf(elem, sizeof elem, "%s", path);
    static const double LOW[] = {
        0, -128.0, 0, -32768.0, 0, -2147483648.0, 0, -9223372036854775808.0, 0};
    static const double HIGH[] = {0,
                                  127.0,
                                  255.0,
                                  32767.0,
                                  65535.0,
                                  2147483647.0,
                                  4294967295.0,
                                  9223372036854775807.0,
                                  18446744073709551615.0};
    if (!isfinite(d) || d != floor(d) || d < LOW[f->type] || d > HIGH[f->type] ||
        (f->type >= LNM_INT64 && d >= HIGH[f->type]))
        field_error(elem, "%s cannot hold %.17g", lnm_type_name(f->type), d);
    switch (f->type) {
    case LNM_INT8:
        *(int8_t*)dst = (int8_t)d;
        break;
    case LNM_UINT8:
        *(uint8_t*)dst = (uint8_t)d;
        break;
    case LNM_INT16: {
        int16_t x = (int16_t)d;
        memcpy(dst, &x, 2);
        break;
    }
    case LNM_UINT16: {
        uint16_t x = (uint16_t)d;
        memcpy(dst, &x, 2);
        break;
    }
    case LNM_INT32: {
        int32_t x = (int32_t)d;
        memcpy(dst, &x, 4);
        break;
    }
    case LNM_UINT32: {
        uint32_t x = (uint32_t)d;
        memcpy(dst, &x, 4);
        break;
    }
    case LNM_INT64: {
        int64_t x = (int64_t)d;
        memcpy(dst, &x, 8);
        break;
    }
    case LNM_UINT64: {
        uint64_t x = (uint64_t)d;
        memcpy(dst, &x, 8);
        break;
    }
    default:
        break;
    }
}

static void pack_record(const lnm_node* rec, const mxArray* value, size_t index, char* dst,
                        const char* path);

/* How many elements `value` gives field f (its static count is checked by the caller);
 * a value of the wrong class is an error naming the field. */
static size_t elements_of(const lnm_node* f, const mxArray* v, const char* path)
{
    char decl[96];
    int ok;
    if (f->type == LNM_RECORD)
        ok = mxIsStruct(v);
    else if (f->type == LNM_CHAR)
        ok = mxIsChar(v);
    else
        ok = (mxIsNumeric(v) || mxIsLogical(v)) && !mxIsComplex(v) && !mxIsSparse(v);
    if (!ok)
        mexErrMsgIdAndTxt("ln:field", "%s: expected %s (%s), got %s%s", path,
                          f->type == LNM_RECORD ? "a struct"
                          : f->type == LNM_CHAR ? "char"
                                                : "real numbers",
                          declared(f, decl, sizeof decl), mxIsComplex(v) ? "complex " : "",
                          mxGetClassName(v));
    return mxGetNumberOfElements(v);
}

/* Packs n elements of field f from v at dst. */
static void pack_elements(const lnm_node* f, const mxArray* v, size_t n, char* dst,
                          const char* path)
{
    if (f->type == LNM_RECORD) {
        for (size_t i = 0; i < n; i++) {
            char elem[PATH_MAX_LEN];
            if (n > 1 || f->dynamic)
                snprintf(elem, sizeof elem, "%s(%zu)", path, i + 1);
            else
                snprintf(elem, sizeof elem, "%s", path);
            pack_record(f, v, i, dst + i * f->elem_size, elem);
        }
    } else if (f->type == LNM_CHAR) {
        char* text = mxArrayToString(v);
        if (text == NULL)
            mexErrMsgIdAndTxt("ln:field", "%s: cannot convert the text", path);
        memcpy(dst, text, strlen(text) < n ? strlen(text) : n);
        mxFree(text);
    } else {
        for (size_t i = 0; i < n; i++)
            store_number(f, dst + i * f->elem_size, v, i, path);
    }
}

static void pack_field(const lnm_node* f, const mxArray* v, char* dst, const char* path)
{
    size_t n = elements_of(f, v, path);
    char decl[96];
    if (f->dynamic) {
        if (n > UINT32_MAX)
            mexErrMsgIdAndTxt("ln:field", "%s: too many elements", path);
        char* data = NULL;
        if (f->type == LNM_CHAR) {
            data = mxArrayToString(v); /* the bytes of the text, maybe more than n chars */
            if (data == NULL)
                mexErrMsgIdAndTxt("ln:field", "%s: cannot convert the text", path);
            n = strlen(data);
        } else if (n) {
            data = mxCalloc(n, f->elem_size);
            pack_elements(f, v, n, data, path);
        }
        uint32_t count = (uint32_t)n;
        memcpy(dst, &count, 4);
        memcpy(dst + 4, &data, sizeof data);
        return;
    }
    if (f->type == LNM_CHAR) {
        if (n > f->count)
            mexErrMsgIdAndTxt("ln:field", "%s: %s holds at most %u characters, got %zu", path,
                              declared(f, decl, sizeof decl), (unsigned)f->count, n);
    } else if (n != f->count) {
        char got[64];
        snprintf(got, sizeof got, "%zu", n);
        mexErrMsgIdAndTxt("ln:field", "%s: expected %u element%s (%s), got %s", path,
                          (unsigned)f->count, f->count == 1 ? "" : "s",
                          declared(f, decl, sizeof decl), got);
    }
    pack_elements(f, v, f->count, dst, path);
}

static void pack_record(const lnm_node* rec, const mxArray* value, size_t index, char* dst,
                        const char* path)
{
    int nf = mxGetNumberOfFields(value);
    for (int k = 0; k < nf; k++) {
        const char* name = mxGetFieldNameByNumber(value, k);
        size_t i = 0;
        while (i < rec->nfields && strcmp(rec->fields[i].name, name) != 0)
            i++;
        if (i == rec->nfields) {
            char where[PATH_MAX_LEN];
            snprintf(where, sizeof where, "%s.%s", path, name);
            mexErrMsgIdAndTxt("ln:field", "%s: unknown field (the md has no field '%s')", where,
                              name);
        }
    }
    for (size_t i = 0; i < rec->nfields; i++) {
        const lnm_node* f = &rec->fields[i];
        char where[PATH_MAX_LEN];
        snprintf(where, sizeof where, "%s.%s", path, f->name);
        const mxArray* v = mxGetField(value, (mwIndex)index, f->name);
        if (v == NULL)
            mexErrMsgIdAndTxt("ln:field", "%s: missing field", where);
        pack_field(f, v, dst + f->offset, where);
    }
}

void lnm_pack(const lnm_node* rec, const mxArray* value, void* dst, const char* what)
{
    if (!mxIsStruct(value) || mxGetNumberOfElements(value) != 1)
        mexErrMsgIdAndTxt("ln:field", "%s: expected a 1x1 struct", what);
    memset(dst, 0, rec->elem_size);
    pack_record(rec, value, 0, dst, what);
}

static mxArray* unpack_elements(const lnm_node* f, const char* src, size_t n);

static void unpack_into(const lnm_node* rec, const char* src, mxArray* out, size_t index)
{
    for (size_t i = 0; i < rec->nfields; i++) {
        const lnm_node* f = &rec->fields[i];
        const char* at = src + f->offset;
        mxArray* v;
        if (f->dynamic) {
            uint32_t count;
            const char* data;
            memcpy(&count, at, 4);
            memcpy(&data, at + 4, sizeof data);
            v = unpack_elements(f, data, data ? count : 0);
        } else {
            v = unpack_elements(f, at, f->count);
        }
        mxSetFieldByNumber(out, (mwIndex)index, (int)i, v);
    }
}

static mxArray* unpack_elements(const lnm_node* f, const char* src, size_t n)
{
    if (f->type == LNM_RECORD) {
        mxArray* s = mxCreateStructMatrix(1, n, (int)f->nfields, f->field_names);
        for (size_t i = 0; i < n; i++)
            unpack_into(f, src + i * f->elem_size, s, i);
        return s;
    }
    if (f->type == LNM_CHAR) {
        size_t len = 0;
        while (len < n && src[len] != '\0')
            len++;
        char* text = mxMalloc(len + 1);
        memcpy(text, src, len);
        text[len] = '\0';
        mxArray* s = mxCreateString(text);
        mxFree(text);
        return s;
    }
    mxArray* a = mxCreateNumericMatrix(1, n, class_of(f->type), mxREAL);
    if (n)
        memcpy(mxGetData(a), src, n * f->elem_size);
    return a;
}

mxArray* lnm_unpack(const lnm_node* rec, const void* src)
{
    mxArray* s = mxCreateStructMatrix(1, 1, (int)rec->nfields, rec->field_names);
    unpack_into(rec, src, s, 0);
    return s;
}
