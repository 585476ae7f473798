/* control.c — ln_control: one CONTROL request (a JSON command) to the manager and its
 * CONTROL_RESULT, with a refusal turned into an error code and the manager's reason. */
#include <stdlib.h>
#include <string.h>

#include "client_internal.h"
#include "json_scan.h"

/* The code a refusal names in its "code" member ("ELIMIT", ...), else LN_EREFUSED. */
static int refusal_code(const char* json)
{
    char name[32];
    if (ln_json_string(json, "code", name, sizeof name) == 0) {
        for (int code = -1; code >= -ln_error_count(); code--)
            if (strcmp(ln_error_name(code), name) == 0)
                return code;
    }
    return LN_EREFUSED;
}

int ln_control(ln_client* clnt, const char* command, char** result)
{
    if (result != NULL)
        *result = NULL;
    int rc = ln_client_check(clnt);
    if (rc != LN_OK)
        return rc;
    if (command == NULL)
        return ln_set_error(clnt, LN_EINVAL, "ln_control: command is NULL");
    ln_wbuf body;
    ln_wbuf_init(&body);
    ln_msg_control request = {.command = ln_strv_of(command)};
    ln_msg_control_write_after_id(&body, &request);
    uint16_t type;
    ln_rbuf reply;
    rc = ln_client_request(clnt, LN_MSG_CONTROL, &body, &type, &reply);
    ln_wbuf_free(&body);
    if (rc != LN_OK)
        return ln_set_error(clnt, rc, "control command: %s", ln_last_error());
    ln_msg_control_result answer;
    if (ln_msg_control_result_read_after_id(&reply, &answer) != LN_OK)
        return ln_set_error(clnt, LN_EPROTOCOL, "control command: malformed CONTROL_RESULT");
    char* copy = malloc(answer.result.len + 1);
    if (copy == NULL)
        return ln_set_error(clnt, LN_ENOMEM, "control command: out of memory");
    ln_strv_copy(answer.result, copy, answer.result.len + 1);
    int ok = ln_json_bool(copy, "ok");
    if (ok != 1) {
        char reason[LN_ERROR_TEXT_MAX];
        if (ln_json_string(copy, "error", reason, sizeof reason) != 0)
            strcpy(reason, ok == 0 ? "no reason given"
                                   : "the answer is not a JSON object "
                                     "with \"ok\"");
        rc = ok == 0 ? refusal_code(copy) : LN_EPROTOCOL;
        free(copy);
        return ln_set_error(clnt, rc, "%s", reason);
    }
    if (result != NULL)
        *result = copy;
    else
        free(copy);
    return LN_OK;
}

void ln_free(void* p) { free(p); }
