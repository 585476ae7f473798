/* print_names.c — prints libln's names (naming.h) for each instance given as an argument, one
 * tab-separated line each: sanitized instance, segment prefix, segment 7.2, segment 7.2 with
 * tag "h1", runtime directory, service socket 42/3 in it.  tests/python/naming compares them
 * with links_and_nodes.naming's. */
#include <stdio.h>

#include "naming.h"

int main(int argc, char** argv)
{
    for (int i = 1; i < argc; i++) {
        char safe[512], prefix[512], seg[512], tagged[512], dir[512], sock[600];
        size_t parent;
        ln_name_instance(argv[i], safe, sizeof safe);
        if (ln_name_segment_prefix(argv[i], prefix, sizeof prefix) != 0 ||
            ln_name_segment(argv[i], 7, 2, NULL, seg, sizeof seg) != 0 ||
            ln_name_segment(argv[i], 7, 2, "h1", tagged, sizeof tagged) != 0 ||
            ln_name_runtime_dir(argv[i], dir, sizeof dir, &parent) != 0 ||
            ln_name_service_socket(dir, 42, 3, sock, sizeof sock) != 0) {
            fprintf(stderr, "print_names: a name of '%s' is too long\n", argv[i]);
            return 1;
        }
        printf("%s\t%s\t%s\t%s\t%s\t%.*s\t%s\n", safe, prefix, seg, tagged, dir, (int)parent, dir,
               sock);
    }
    return 0;
}
