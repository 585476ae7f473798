/* event_common.c — helpers both sides of events use: the event name check, the signatures of
 * a handler's service, the reply record, and JSON quoting and hex for the manager's event
 * commands. */
#include <stdlib.h>
#include <string.h>

#include "event_internal.h"

int ln_event_check_name(ln_client* clnt, const char* what, const char* event)
{
    if (event == NULL)
        return ln_set_error(clnt, LN_EINVAL, "%s: the event name is NULL", what);
    size_t n = strlen(event);
    if (n == 0 || n > LN_EVENT_MAX_NAME)
        return ln_set_error(clnt, LN_EINVAL, "%s: event name of %zu bytes, must be 1..%d", what, n,
                            LN_EVENT_MAX_NAME);
    if (event[0] == '.')
        return ln_set_error(clnt, LN_EINVAL, "%s: event name \"%s\" must not start with '.'", what,
                            event);
    for (const char* p = event; *p != '\0'; p++) {
        char c = *p;
        if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
              strchr("_.:/-", c) != NULL))
            return ln_set_error(clnt, LN_EINVAL,
                                "%s: event name \"%s\" may only contain A-Z a-z 0-9 _ . : / -",
                                what, event);
    }
    return LN_OK;
}

int ln_event_parse_signature(ln_client* clnt, const char* md_name, const char* signature,
                             ln_sig** connect, ln_sig** call, char** handler_signature)
{
    char *a = NULL, *b = NULL;
    *connect = *call = NULL;
    *handler_signature = NULL;
    int rc = ln_sig_split(signature, &a, &b);
    if (rc != LN_OK)
        rc = ln_set_error(clnt, rc,
                          "event md \"%s\": %s (an event signature is "
                          "\"connect|call\")",
                          md_name, ln_last_error());
    if (rc == LN_OK && (rc = ln_sig_parse(a, connect)) != LN_OK)
        rc = ln_set_error(clnt, rc, "event md \"%s\": connect signature: %s", md_name,
                          ln_last_error());
    if (rc == LN_OK && (rc = ln_sig_parse(b, call)) != LN_OK)
        rc =
            ln_set_error(clnt, rc, "event md \"%s\": call signature: %s", md_name, ln_last_error());
    if (rc == LN_OK) {
        size_t n = strlen(b) + 1 + sizeof LN_EVENT_REPLY_SIG;
        *handler_signature = malloc(n);
        if (*handler_signature == NULL)
            rc = ln_set_error(clnt, LN_ENOMEM, "event md \"%s\": out of memory", md_name);
        else
            snprintf(*handler_signature, n, "%s|%s", b, LN_EVENT_REPLY_SIG);
    }
    free(a);
    free(b);
    if (rc != LN_OK) {
        ln_sig_free(*connect);
        ln_sig_free(*call);
        *connect = *call = NULL;
    }
    return rc;
}

void ln_event_reply_pack(uint8_t out[LN_EVENT_REPLY_SIZE], int has_reply, uint32_t len,
                         const void* data)
{
    out[0] = has_reply ? 1 : 0;
    memcpy(out + 1, &len, sizeof len);
    memcpy(out + 5, &data, sizeof data);
}

void ln_event_reply_unpack(const uint8_t in[LN_EVENT_REPLY_SIZE], int* has_reply, uint32_t* len,
                           const uint8_t** data)
{
    *has_reply = in[0] != 0;
    memcpy(len, in + 1, sizeof *len);
    memcpy(data, in + 5, sizeof *data);
}

void ln_event_json_quote(FILE* f, const char* s)
{
    fputc('"', f);
    for (const unsigned char* p = (const unsigned char*)s; *p != '\0'; p++) {
        if (*p == '"' || *p == '\\')
            fprintf(f, "\\%c", *p);
        else if (*p < 0x20)
            fprintf(f, "\\u%04x", *p);
        else
            fputc(*p, f);
    }
    fputc('"', f);
}

void ln_event_hex(const uint8_t* data, size_t len, char* out)
{
    static const char digits[] = "0123456789abcdef";
    for (size_t i = 0; i < len; i++) {
        out[2 * i] = digits[data[i] >> 4];
        out[2 * i + 1] = digits[data[i] & 15];
    }
    out[2 * len] = '\0';
}

static int nibble(char c)
{
    if (c >= '0' && c <= '9')
        return c - '0';
    if (c >= 'a' && c <= 'f')
        return c - 'a' + 10;
    if (c >= 'A' && c <= 'F')
        return c - 'A' + 10;
    return -1;
}

int ln_event_unhex(const char* hex, uint8_t* out, size_t max, size_t* len)
{
    size_t n = strlen(hex);
    if (n % 2 != 0 || n / 2 > max)
        return -1;
    for (size_t i = 0; i < n / 2; i++) {
        int hi = nibble(hex[2 * i]), lo = nibble(hex[2 * i + 1]);
        if (hi < 0 || lo < 0)
            return -1;
        out[i] = (uint8_t)(hi << 4 | lo);
    }
    *len = n / 2;
    return 0;
}
