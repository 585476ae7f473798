/* The trivial process of bench/startup: prints "ready NAME" (NAME is argv[2]; argv[1] is the
 * run's token, which lets the benchmark find strays), then waits for SIGTERM or SIGINT and
 * exits with status 0. */
#define _POSIX_C_SOURCE 200809L
#include <signal.h>
#include <stdio.h>

int main(int argc, char **argv)
{
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGTERM);
    sigaddset(&set, SIGINT);
    /* Blocked before "ready", so a stop that comes right after it is not lost. */
    sigprocmask(SIG_BLOCK, &set, NULL);
    printf("ready %s\n", argc > 2 ? argv[2] : "");
    fflush(stdout);
    int sig;
    sigwait(&set, &sig);
    return 0;
}
