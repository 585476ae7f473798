/* mex_convert.h — MATLAB/Octave values to packed md structs and back, by a run-time layout
 * (mex_layout.h).  Errors raise a MATLAB error (id "ln:field") naming the field; everything
 * these functions allocate comes from mxMalloc, so an error leaks nothing. */
#ifndef LN_MEX_CONVERT_H
#define LN_MEX_CONVERT_H

#include "mex.h"
#include "mex_layout.h"

/* Packs the 1x1 struct `value` into dst[rec->elem_size] (zeroed first).  Dynamic fields point
 * at mxMalloc'd memory, freed when the MEX call returns.  `what` names the value ("request"). */
void lnm_pack(const lnm_node* rec, const mxArray* value, void* dst, const char* what);
/* A 1x1 struct with the fields of src[rec->elem_size]. */
mxArray* lnm_unpack(const lnm_node* rec, const void* src);

#endif /* LN_MEX_CONVERT_H */
