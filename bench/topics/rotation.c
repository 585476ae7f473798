/* rotation.c — why a ring that rotates through its slots is slow for large samples: one
 * process writes a sample from a source buffer into slot i mod N of a shared mapping and
 * copies it out again, for N = 1, 2, 3, 17 (a queue of 16) and 65, with 4 KiB pages and
 * with transparent huge pages (madvise, private anonymous memory), so the cost of cache
 * residency and of TLB reach can be told apart where the CPU has no hardware counters.
 * Goal it serves: the hot-slot choice of the topic ring (docs/topics.md, "Before and
 * after"); the baseline is N = 1 in the same run.  Prints a table, writes JSON to OUT. */
#include <inttypes.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <time.h>

static const char usage[] = "usage: rotation SIZE ROUNDS OUT.json   (SIZE in bytes)\n";

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + (double)t.tv_nsec * 1e-9;
}

/* Microseconds per write + read of one sample through `slots` slots (median of 5 runs). */
static double measure(size_t size, unsigned slots, unsigned rounds, int huge, uint8_t* src,
                      uint8_t* dst)
{
    int flags = huge ? MAP_PRIVATE | MAP_ANONYMOUS : MAP_SHARED | MAP_ANONYMOUS;
    uint8_t* ring = mmap(NULL, size * slots, PROT_READ | PROT_WRITE, flags, -1, 0);
    if (ring == MAP_FAILED) {
        perror("rotation: mmap");
        exit(1);
    }
    if (huge)
        madvise(ring, size * slots, MADV_HUGEPAGE);
    memset(ring, 0, size * slots); /* every page present before timing */
    double runs[5];
    for (int r = 0; r < 5; r++) {
        double t0 = now_s();
        for (unsigned i = 0; i < rounds; i++) {
            uint8_t* slot = ring + (size_t)(i % slots) * size;
            memcpy(slot, src, size);
            memcpy(dst, slot, size);
        }
        runs[r] = (now_s() - t0) / rounds * 1e6;
    }
    munmap(ring, size * slots);
    for (int i = 1; i < 5; i++) /* insertion sort of five */
        for (int j = i; j > 0 && runs[j] < runs[j - 1]; j--) {
            double t = runs[j];
            runs[j] = runs[j - 1];
            runs[j - 1] = t;
        }
    return runs[2];
}

int main(int argc, char** argv)
{
    if (argc != 4) {
        fputs(usage, stderr);
        return 2;
    }
    size_t size = strtoull(argv[1], NULL, 10);
    unsigned rounds = (unsigned)strtoul(argv[2], NULL, 10);
    if (size < 64 || rounds == 0) {
        fputs(usage, stderr);
        return 2;
    }
    uint8_t* src = malloc(size);
    uint8_t* dst = malloc(size);
    if (!src || !dst)
        return 1;
    memset(src, 0x5a, size);
    memset(dst, 0, size);
    static const unsigned counts[] = {1, 2, 3, 17, 65};
    enum { N = sizeof counts / sizeof counts[0] };
    double pages4k[N], huge[N];
    printf("write + read of %zu B through N rotating slots, µs per sample (median of 5 x %u)\n",
           size, rounds);
    printf("%6s %10s %8s %12s %8s\n", "slots", "4 KiB", "vs N=1", "huge pages", "vs N=1");
    for (unsigned i = 0; i < N; i++) {
        pages4k[i] = measure(size, counts[i], rounds, 0, src, dst);
        huge[i] = measure(size, counts[i], rounds, 1, src, dst);
        printf("%6u %10.1f %8.2f %12.1f %8.2f\n", counts[i], pages4k[i], pages4k[i] / pages4k[0],
               huge[i], huge[i] / huge[0]);
    }
    FILE* out = fopen(argv[3], "w");
    if (!out) {
        perror(argv[3]);
        return 1;
    }
    fprintf(out, "{\"size\": %zu, \"rounds\": %u, \"cases\": [", size, rounds);
    for (unsigned i = 0; i < N; i++)
        fprintf(out, "%s{\"slots\": %u, \"us_4k\": %.3f, \"us_huge\": %.3f}", i ? ", " : "",
                counts[i], pages4k[i], huge[i]);
    fprintf(out, "]}\n");
    fclose(out);
    printf("wrote %s\n", argv[3]);
    free(src);
    free(dst);
    return 0;
}
