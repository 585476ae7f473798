/* param_history.c — the change stream of a parameter block: the last LN_PARAM_HISTORY
 * changes (set, config, reset) with their generation, time and values, which the service's
 * op "changes" hands out from a generation on (`ln_manager param changes`).  Service side
 * only, under the block's lock. */
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "param_internal.h"

void ln_param_history_add(ln_parameter_block* b, const char* op, const uint8_t* which,
                          const uint8_t* values)
{
    ln_pbuf j;
    ln_pbuf_init(&j);
    ln_pbuf_add(&j, "\"parameters\": [");
    for (uint32_t i = 0, k = 0; i < b->n; i++)
        if (which[i]) {
            ln_pbuf_add(&j, "%s", k++ ? ", " : "");
            ln_pbuf_quote(&j, b->params[i].name, strlen(b->params[i].name));
        }
    ln_pbuf_add(&j, "]");
    if (values != NULL) {
        size_t names_end = j.len;
        ln_pbuf_add(&j, ", \"values\": {");
        for (uint32_t i = 0, k = 0; i < b->n && j.len <= LN_PARAM_HISTORY_VALUES; i++)
            if (which[i]) {
                const ln_param* p = &b->params[i];
                ln_pbuf_add(&j, "%s", k++ ? ", " : "");
                ln_pbuf_quote(&j, p->name, strlen(p->name));
                ln_pbuf_add(&j, ": ");
                ln_param_write(&j, p, values + p->offset);
            }
        ln_pbuf_add(&j, "}");
        if (j.len > LN_PARAM_HISTORY_VALUES && !j.failed) { /* too big to keep: names only */
            j.len = names_end;
            j.data[j.len] = '\0';
        }
    }
    ln_param_change* c = &b->history[b->generation % LN_PARAM_HISTORY];
    free(c->json);
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    c->gen = b->generation;
    c->time_ns = (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
    c->op = op;
    c->json = j.failed ? NULL : j.data;
    if (j.failed)
        ln_pbuf_free(&j);
}

void ln_param_history_write(const ln_parameter_block* b, uint64_t since, ln_pbuf* out)
{
    uint64_t oldest = b->generation >= LN_PARAM_HISTORY ? b->generation - LN_PARAM_HISTORY + 1 : 1;
    ln_pbuf_add(out, "{\"generation\": %llu, \"oldest\": %llu, \"changes\": [",
                (unsigned long long)b->generation, (unsigned long long)oldest);
    int first = 1;
    for (uint64_t g = since + 1 > oldest ? since + 1 : oldest; g <= b->generation; g++) {
        const ln_param_change* c = &b->history[g % LN_PARAM_HISTORY];
        if (c->gen != g)
            continue;
        ln_pbuf_add(out, "%s{\"generation\": %llu, \"time\": %lld.%09lld, \"op\": \"%s\", %s}",
                    first ? "" : ", ", (unsigned long long)g, (long long)(c->time_ns / 1000000000),
                    (long long)(c->time_ns % 1000000000), c->op,
                    c->json ? c->json : "\"parameters\": []");
        first = 0;
    }
    ln_pbuf_add(out, "]}");
}

void ln_param_history_free(ln_parameter_block* b)
{
    for (int i = 0; i < LN_PARAM_HISTORY; i++) {
        free(b->history[i].json);
        b->history[i].json = NULL;
    }
}
