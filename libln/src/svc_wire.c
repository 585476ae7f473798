/* svc_wire.c — frames of the caller <-> provider protocol, the socket directory and the
 * listening/connecting sockets of services. */
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <arpa/inet.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <time.h>
#include <unistd.h>

#include "svc_wire.h"

#include "naming.h"

int ln_svc_parse_header(const uint8_t header[LN_SVC_HEADER_SIZE], size_t max_payload,
                        uint32_t* body_len, uint16_t* type)
{
    ln_rbuf r;
    ln_rbuf_init(&r, header, LN_SVC_HEADER_SIZE);
    uint32_t length = ln_rbuf_u32(&r);
    uint16_t t = ln_rbuf_u16(&r);
    if (length < 2 || t < LN_SVC_HELLO || t > LN_SVC_SEALED)
        return LN_EPROTOCOL;
    *body_len = length - 2;
    *type = t;
    return (size_t)length - 2 > max_payload + LN_SVC_OVERHEAD ? LN_ETOOBIG : LN_OK;
}

int ln_svc_frame_end(ln_wbuf* b, size_t start)
{
    if (b->failed)
        return b->failed;
    uint64_t length = b->len - start - 4;
    if (length > UINT32_MAX)
        return LN_ETOOBIG;
    for (int i = 0; i < 4; i++)
        b->data[start + (size_t)i] = (uint8_t)(length >> (8 * i));
    return LN_OK;
}

void ln_svc_put_error(ln_wbuf* b, uint32_t call_id, int code, const char* text)
{
    char cut[LN_SVC_MAX_ERROR_TEXT + 1];
    size_t n = strnlen(text ? text : "", LN_SVC_MAX_ERROR_TEXT);
    memcpy(cut, text ? text : "", n);
    /* Back off to a character boundary, then make sure the rest is UTF-8 too. */
    for (int k = 0; k < 3 && n > 0 && !ln_utf8_valid(cut, n); k++)
        n--;
    cut[n] = '\0';
    if (!ln_utf8_valid(cut, n))
        snprintf(cut, sizeof cut, "(error text is not UTF-8)");
    size_t start = ln_proto_frame_begin(b, LN_SVC_ERROR);
    ln_wbuf_u32(b, call_id);
    ln_wbuf_i32(b, code);
    ln_wbuf_str(b, cut);
    ln_svc_frame_end(b, start);
}

/* mkdir with mode 0700 unless it exists as a directory. */
static int private_dir(const char* path)
{
    if (mkdir(path, 0700) != 0 && errno != EEXIST)
        return errno;
    struct stat st;
    if (lstat(path, &st) != 0)
        return errno;
    if (!S_ISDIR(st.st_mode))
        return ENOTDIR;
    if (st.st_uid != geteuid())
        return EPERM;
    return 0;
}

int ln_svc_socket_dir(const char* instance, char* out, size_t size)
{
    size_t parent = 0;
    if (ln_name_runtime_dir(instance, out, size, &parent) != LN_OK)
        return ln_set_error(NULL, LN_ETOOBIG, "service socket directory name is too long");
    int err = 0;
    if (parent > 0) { /* the private parent first: /tmp/ln-<uid> or $XDG_RUNTIME_DIR/ln */
        out[parent] = '\0';
        err = private_dir(out);
        out[parent] = '/';
    }
    if (err == 0)
        err = private_dir(out);
    if (err != 0)
        return ln_set_errno_error(NULL, err, "cannot use service socket directory %s", out);
    return LN_OK;
}

static int fill_unix_addr(const char* path, struct sockaddr_un* addr)
{
    memset(addr, 0, sizeof *addr);
    addr->sun_family = AF_UNIX;
    size_t n = strlen(path);
    if (n == 0 || n >= sizeof addr->sun_path)
        return ENAMETOOLONG;
    memcpy(addr->sun_path, path, n + 1);
    return 0;
}

int ln_svc_listen_unix(const char* path, int* fd)
{
    struct sockaddr_un addr;
    int err = fill_unix_addr(path, &addr);
    if (err != 0)
        return err;
    int s = socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (s < 0)
        return errno;
    if (bind(s, (struct sockaddr*)&addr, sizeof addr) != 0 || listen(s, 128) != 0) {
        err = errno;
        close(s);
        return err;
    }
    *fd = s;
    return 0;
}

int ln_svc_listen_tcp(int* fd, uint16_t* port)
{
    struct sockaddr_in addr;
    memset(&addr, 0, sizeof addr);
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_ANY);
    const char* bind_host = getenv("LN_SERVICE_BIND");
    if (bind_host != NULL && *bind_host != '\0' &&
        inet_pton(AF_INET, bind_host, &addr.sin_addr) != 1)
        return EINVAL;
    int s = socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (s < 0)
        return errno;
    socklen_t len = sizeof addr;
    if (bind(s, (struct sockaddr*)&addr, sizeof addr) != 0 || listen(s, 128) != 0 ||
        getsockname(s, (struct sockaddr*)&addr, &len) != 0) {
        int err = errno;
        close(s);
        return err;
    }
    *fd = s;
    *port = ntohs(addr.sin_port);
    return 0;
}

int ln_svc_connect_unix(const char* path, const struct timespec* deadline, int* fd)
{
    struct sockaddr_un addr;
    int err = fill_unix_addr(path, &addr);
    if (err != 0)
        return err;
    for (;;) {
        /* Blocking connect: on a Unix socket it completes or fails at once, except for a full
         * backlog (EAGAIN), which is retried until the deadline. */
        int s = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
        if (s < 0)
            return errno;
        if (connect(s, (struct sockaddr*)&addr, sizeof addr) == 0) {
            int flags = fcntl(s, F_GETFL);
            if (flags < 0 || fcntl(s, F_SETFL, flags | O_NONBLOCK) != 0) {
                err = errno;
                close(s);
                return err;
            }
            *fd = s;
            return 0;
        }
        err = errno;
        close(s);
        if (err != EAGAIN && err != EINTR)
            return err;
        struct timespec now;
        clock_gettime(CLOCK_MONOTONIC, &now);
        if (deadline != NULL &&
            (now.tv_sec > deadline->tv_sec ||
             (now.tv_sec == deadline->tv_sec && now.tv_nsec >= deadline->tv_nsec)))
            return ETIMEDOUT;
        nanosleep(&(struct timespec){0, 1000000}, NULL);
    }
}
