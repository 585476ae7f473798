/* naming.h — the one home in C of how links_and_nodes names things on a host: the sanitized
 * instance, shared-memory segment names, the runtime directory and service socket names.
 * Python's links_and_nodes.naming follows the same rules; tests/python/naming checks that both
 * give the same names (through tests/c/print_names).  Internal. */
#ifndef LN_NAMING_H
#define LN_NAMING_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The instance as it appears in names: each character but A-Z a-z 0-9 _ - becomes one '_' (a
 * multi-byte UTF-8 character one '_', too), so no '.' or '/' can make one instance's names
 * match another's.  Sanitizing a sanitized name changes nothing.  Writes at most size - 1
 * bytes and a NUL (size > 0); returns the full length, as snprintf does. */
size_t ln_name_instance(const char* instance, char* out, size_t size);

/* "/ln.<sanitized instance>.": every segment of the instance starts so.  LN_OK or LN_ETOOBIG
 * (no error text recorded: callers word it). */
int ln_name_segment_prefix(const char* instance, char* out, size_t size);

/* "/ln.<sanitized instance>.<topic id>.<generation>", with ".<tag>" after it when tag is
 * neither NULL nor "" (segments a daemon makes for another host's topic).  LN_OK or
 * LN_ETOOBIG. */
int ln_name_segment(const char* instance, uint64_t topic_id, uint64_t generation, const char* tag,
                    char* out, size_t size);

/* The instance's runtime directory (not created here): $LN_RUNTIME_DIR (the directory itself),
 * else $XDG_RUNTIME_DIR/ln/<sanitized instance>, else /tmp/ln-<uid>/<sanitized instance>.
 * *parent_len: the length of its private parent directory (to create first, mode 0700), 0 for
 * $LN_RUNTIME_DIR.  LN_OK or LN_ETOOBIG. */
int ln_name_runtime_dir(const char* instance, char* out, size_t size, size_t* parent_len);

/* "<dir>/svc.<pid>.<n>.sock", a service provider's Unix socket.  LN_OK or LN_ETOOBIG. */
int ln_name_service_socket(const char* dir, long pid, unsigned n, char* out, size_t size);

#ifdef __cplusplus
}
#endif

#endif /* LN_NAMING_H */
