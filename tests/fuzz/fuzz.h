/* fuzz.h — what every fuzz target in tests/fuzz exports: the libFuzzer entry point and its
 * seed inputs, built with the product's own encoders (docs/robustness.md, "Fuzzing"). */
#ifndef LN_FUZZ_H
#define LN_FUZZ_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Runs one input; must never crash, hang or leak whatever the bytes.  Returns 0. */
int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

/* Called once per seed with a file name (no directory) and its bytes. */
typedef void ln_fuzz_emit(const char* name, const void* data, size_t size);
void ln_fuzz_seeds(ln_fuzz_emit* emit);

#ifdef __cplusplus
}
#endif

#endif /* LN_FUZZ_H */
