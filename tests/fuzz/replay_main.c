/* replay_main.c — main() for the fuzz targets without libFuzzer (any compiler): replays the
 * given files/directories, by default the target's committed corpus and regressions (what
 * `scons check` runs); `--write-seeds DIR` writes the target's seeds (scripts/fuzz --seeds). */
#define _GNU_SOURCE 1
#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "fuzz.h"

#ifndef LN_FUZZ_NAME
#error "build with -DLN_FUZZ_NAME=\"target\" and -DLN_FUZZ_DIR=\"/path/to/tests/fuzz\""
#endif

static const char* seed_dir;
static int failures;

static void write_seed(const char* name, const void* data, size_t size)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", seed_dir, name);
    FILE* f = fopen(path, "wb");
    if (f == NULL || fwrite(data, 1, size, f) != size || fclose(f) != 0) {
        fprintf(stderr, "%s: cannot write: %s\n", path, strerror(errno));
        failures++;
    }
}

static int run_file(const char* path)
{
    FILE* f = fopen(path, "rb");
    if (f == NULL) {
        fprintf(stderr, "%s: %s\n", path, strerror(errno));
        return -1;
    }
    size_t cap = 4096, len = 0;
    uint8_t* buf = malloc(cap);
    size_t n;
    while (buf != NULL && (n = fread(buf + len, 1, cap - len, f)) > 0) {
        len += n;
        if (len == cap) {
            uint8_t* bigger = realloc(buf, cap *= 2);
            if (bigger == NULL)
                free(buf);
            buf = bigger;
        }
    }
    fclose(f);
    if (buf == NULL) {
        fprintf(stderr, "%s: out of memory\n", path);
        return -1;
    }
    /* An exact-size copy, so the sanitizer build catches reads past the input. */
    uint8_t* input = malloc(len ? len : 1);
    if (input != NULL) {
        memcpy(input, buf, len);
        LLVMFuzzerTestOneInput(input, len);
    }
    free(input);
    free(buf);
    return input != NULL ? 1 : -1;
}

static int by_name(const struct dirent** a, const struct dirent** b)
{
    return strcmp((*a)->d_name, (*b)->d_name);
}

/* Runs a file, or every regular file of a directory (a missing directory has none).  Returns
 * the number of inputs run, or -1. */
static int run_path(const char* path)
{
    struct stat st;
    if (stat(path, &st) != 0)
        return errno == ENOENT ? 0 : -1;
    if (!S_ISDIR(st.st_mode))
        return run_file(path);
    struct dirent** names;
    int n = scandir(path, &names, NULL, by_name);
    if (n < 0)
        return -1;
    int count = 0;
    for (int i = 0; i < n; i++) {
        char file[4096];
        snprintf(file, sizeof file, "%s/%s", path, names[i]->d_name);
        if (names[i]->d_name[0] != '.' && stat(file, &st) == 0 && S_ISREG(st.st_mode)) {
            int rc = run_file(file);
            count = rc < 0 || count < 0 ? -1 : count + rc;
        }
        free(names[i]);
    }
    free(names);
    return count;
}

int main(int argc, char** argv)
{
    if (argc == 3 && strcmp(argv[1], "--write-seeds") == 0) {
        seed_dir = argv[2];
        ln_fuzz_seeds(write_seed);
        return failures ? 1 : 0;
    }
    const char* defaults[] = {LN_FUZZ_DIR "/corpus/" LN_FUZZ_NAME,
                              LN_FUZZ_DIR "/regressions/" LN_FUZZ_NAME};
    const char* const* paths = argc > 1 ? (const char* const*)argv + 1 : defaults;
    int npaths = argc > 1 ? argc - 1 : 2;
    int total = 0;
    for (int i = 0; i < npaths; i++) {
        int n = run_path(paths[i]);
        if (n < 0) {
            fprintf(stderr, "%s: cannot read\n", paths[i]);
            return 1;
        }
        total += n;
    }
    if (total == 0) {
        fprintf(stderr, "%s: no inputs found\n", LN_FUZZ_NAME);
        return 1;
    }
    printf("%s: %d inputs replayed\n", LN_FUZZ_NAME, total);
    return 0;
}
