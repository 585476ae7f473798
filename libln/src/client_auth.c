/* client_auth.c — the client key file and the HMAC-SHA256 proofs of admission by key
 * (docs/security.md, "Client admission to the manager"); the manager's side is
 * python/links_and_nodes/manager/registry/admission.py, which must compute the same bytes. */
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

#include "client_auth.h"
#include "ln/ln.h"

int ln_auth_from_hex(const char* s, size_t len, uint8_t out[LN_AUTH_BYTES])
{
    size_t bin_len = 0;
    const char* end = NULL;
    if (len != LN_AUTH_HEX ||
        sodium_hex2bin(out, LN_AUTH_BYTES, s, len, NULL, &bin_len, &end) != 0 ||
        bin_len != LN_AUTH_BYTES || end != s + len)
        return -1;
    return 0;
}

void ln_auth_to_hex(const uint8_t in[LN_AUTH_BYTES], char out[LN_AUTH_HEX + 1])
{
    static const char digits[] = "0123456789abcdef";
    for (size_t i = 0; i < LN_AUTH_BYTES; i++) {
        out[2 * i] = digits[in[i] >> 4];
        out[2 * i + 1] = digits[in[i] & 0xf];
    }
    out[LN_AUTH_HEX] = '\0';
}

/* The key file's path into `path`: 1 if named by the environment, 0 for the default one,
 * -1 if there is none to try. */
static int key_path(char* path, size_t size)
{
    const char* env = getenv("LN_CLIENT_KEY_FILE");
    if (env != NULL && env[0] != '\0') {
        snprintf(path, size, "%s", env);
        return 1;
    }
    const char* home = getenv("HOME");
    if (home == NULL || home[0] == '\0')
        return -1;
    snprintf(path, size, "%s/.config/links_and_nodes/client.key", home);
    return 0;
}

/* Reads the opened key file `fd` (checked like ln_daemon's, ln_daemon/auth.cpp). */
static int read_key(int fd, const char* path, uint8_t key[LN_AUTH_BYTES], char* err,
                    size_t err_size)
{
    struct stat st;
    if (fstat(fd, &st) != 0) {
        snprintf(err, err_size, "cannot stat client key file '%s': %s", path, strerror(errno));
        return LN_EPERM;
    }
    if (!S_ISREG(st.st_mode)) {
        snprintf(err, err_size, "client key file '%s' is not a regular file", path);
        return LN_EPERM;
    }
    if (st.st_uid != geteuid()) {
        snprintf(err, err_size, "client key file '%s' is owned by uid %u, not by uid %u", path,
                 (unsigned)st.st_uid, (unsigned)geteuid());
        return LN_EPERM;
    }
    if (st.st_mode & 077) {
        snprintf(err, err_size,
                 "client key file '%s' is accessible by group or others (mode %04o); it must "
                 "be private: chmod 600 '%s'",
                 path, (unsigned)(st.st_mode & 07777), path);
        return LN_EPERM;
    }
    char text[130];
    ssize_t n = read(fd, text, sizeof text);
    size_t len = n > 0 ? (size_t)n : 0;
    if (len > 0 && text[len - 1] == '\n')
        len--;
    int bad = n < 0 || ln_auth_from_hex(text, len, key) != 0;
    sodium_memzero(text, sizeof text);
    if (bad) {
        sodium_memzero(key, LN_AUTH_BYTES);
        snprintf(err, err_size,
                 "client key file '%s' holds no valid key: it must contain exactly 64 hex "
                 "digits (32 bytes), optionally followed by a newline",
                 path);
        return LN_EPERM;
    }
    return LN_OK;
}

int ln_auth_load_key(uint8_t key[LN_AUTH_BYTES], char* path, size_t path_size, char* err,
                     size_t err_size)
{
    int named = key_path(path, path_size);
    if (named < 0) {
        snprintf(err, err_size, "no client key: LN_CLIENT_KEY_FILE is not set and HOME is unknown");
        return LN_ENOTFOUND;
    }
    int fd = open(path, O_RDONLY | O_CLOEXEC | O_NOCTTY);
    if (fd < 0 && errno == ENOENT && !named) {
        snprintf(err, err_size,
                 "no client key: LN_CLIENT_KEY_FILE is not set and '%s' does not "
                 "exist",
                 path);
        return LN_ENOTFOUND;
    }
    if (fd < 0) {
        snprintf(err, err_size, "cannot open client key file '%s': %s", path, strerror(errno));
        return LN_EPERM;
    }
    int rc = read_key(fd, path, key, err, err_size);
    close(fd);
    return rc;
}

static void update_str(crypto_auth_hmacsha256_state* st, const char* s)
{
    static const unsigned char zero = 0;
    crypto_auth_hmacsha256_update(st, (const unsigned char*)s, strlen(s));
    crypto_auth_hmacsha256_update(st, &zero, 1);
}

void ln_auth_mac(const uint8_t key[LN_AUTH_BYTES], const char* label, const char* instance,
                 const char* name, const uint8_t manager_nonce[LN_AUTH_BYTES],
                 const uint8_t client_nonce[LN_AUTH_BYTES], uint8_t out[LN_AUTH_BYTES])
{
    crypto_auth_hmacsha256_state st;
    crypto_auth_hmacsha256_init(&st, key, LN_AUTH_BYTES);
    update_str(&st, label);
    update_str(&st, instance);
    update_str(&st, name);
    crypto_auth_hmacsha256_update(&st, manager_nonce, LN_AUTH_BYTES);
    crypto_auth_hmacsha256_update(&st, client_nonce, LN_AUTH_BYTES);
    crypto_auth_hmacsha256_final(&st, out);
    sodium_memzero(&st, sizeof st);
}

void ln_auth_random(uint8_t* out, size_t n)
{
    /* idempotent and thread-safe; randombytes_buf works even if it failed */
    if (sodium_init() < 0)
        memset(out, 0, n);
    randombytes_buf(out, n);
}

int ln_auth_differ(const uint8_t a[LN_AUTH_BYTES], const uint8_t b[LN_AUTH_BYTES])
{
    return sodium_memcmp(a, b, LN_AUTH_BYTES) != 0;
}

void ln_auth_wipe(void* p, size_t n) { sodium_memzero(p, n); }
