/* test_client_options.c — where a client finds its manager and what it calls itself:
 * ln_client_options, "-ln_manager HOST:PORT" in argv, $LN_MANAGER and their order, ":PORT",
 * [IPv6]:PORT, every malformed address, LN_PROGRAM_NAME and argv[0], bad arguments, and a
 * manager that is not there. */
#define _GNU_SOURCE 1 /* libln's own sources are built with it */

#include "fake_manager.h"

/* A port on 127.0.0.1 that nobody listens on (bound once, then released). */
static int unused_port(void)
{
    struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = 0};
    sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof sa;
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    LN_CHECK(fd >= 0 && bind(fd, (struct sockaddr*)&sa, sizeof sa) == 0 &&
             getsockname(fd, (struct sockaddr*)&sa, &len) == 0);
    close(fd);
    return ntohs(sa.sin_port);
}

static void test_connection_refused(void)
{
    char address[64], expected[128];
    int port = unused_port();
    snprintf(address, sizeof address, "127.0.0.1:%d", port);
    snprintf(expected, sizeof expected, "cannot connect to manager %s: Connection refused",
             address);
    ln_client_options o;
    ln_client_options_init(&o);
    o.manager = address;
    ln_client* c = NULL;
    LN_CHECK_EQ(ln_client_create(&c, "x", &o), LN_ECONNECTION);
    LN_CHECK(c == NULL);
    LN_CHECK(error_has(expected));
    /* Where the address came from is part of the story. */
    setenv("LN_MANAGER", address, 1);
    LN_CHECK_EQ(ln_client_create(&c, "x", NULL), LN_ECONNECTION);
    LN_CHECK(error_has(" (from LN_MANAGER): Connection refused"));
    unsetenv("LN_MANAGER");
}

/* Connects with `o` (the fake must be what it points to), disconnects, and checks the name
 * the client sent. */
static void expect_connect(const char* name, const ln_client_options* o, struct fake* f,
                           const char* sent_name)
{
    ln_client* c = connect_ok(name, o);
    ln_client_destroy(c);
    fake_stop(f);
    LN_CHECK(f->connected);
    LN_CHECK_STREQ(f->hello_name, sent_name);
}

static void test_address_sources(void)
{
    struct fake f;
    char bogus_env[] = "127.0.0.1:notaport";
    char port_only[16];
    ln_client_options o;

    /* ":PORT" is localhost. */
    fake_start(&f, script_welcome, 0);
    o = fake_options(&f);
    snprintf(port_only, sizeof port_only, ":%d", f.port);
    o.manager = port_only;
    expect_connect("cam", &o, &f, "cam");

    /* -ln_manager in argv; the name defaults to argv[0] without its directory. */
    fake_start(&f, script_welcome, 0);
    char* argv[] = {"/opt/robot/bin/arm_ctrl", "-v", "-ln_manager", f.address, NULL};
    ln_client_options_init(&o);
    o.argc = 4;
    o.argv = argv;
    setenv("LN_MANAGER", bogus_env, 1); /* argv wins over the environment */
    expect_connect(NULL, &o, &f, "arm_ctrl");

    /* The options win over argv and the environment. */
    fake_start(&f, script_welcome, 0);
    char* bad_argv[] = {"prog", "-ln_manager", "nonsense", NULL};
    o = fake_options(&f);
    o.argc = 3;
    o.argv = bad_argv;
    expect_connect("", &o, &f, "prog");

    /* $LN_MANAGER with no options at all; the name defaults to "client". */
    fake_start(&f, script_welcome, 0);
    setenv("LN_MANAGER", f.address, 1);
    expect_connect(NULL, NULL, &f, "client");
    unsetenv("LN_MANAGER");
}

static void test_program_name_override(void)
{
    struct fake f;
    fake_start(&f, script_welcome, 0);
    ln_client_options o = fake_options(&f);
    setenv("LN_PROGRAM_NAME", "from_env", 1);
    expect_connect("cam", &o, &f, "from_env");
    unsetenv("LN_PROGRAM_NAME");
}

static void test_bad_addresses(void)
{
    const char* bad[] = {"nohost",      "host:",    "host:0",   "host:65536",
                         "host:123456", "host:12a", "host:+80", "host: 80",
                         "::1:5555",    "[::1]",    ":",        ""};
    unsetenv("LN_MANAGER");
    for (size_t i = 0; i < LN_ARRAY_SIZE(bad); i++) {
        ln_client_options o;
        ln_client_options_init(&o);
        o.manager = bad[i];
        ln_client* c = NULL;
        LN_CHECK_EQ(ln_client_create(&c, "x", &o), LN_EINVAL);
        LN_CHECK(c == NULL);
        /* "" counts as not given, so it is the no-address error */
        LN_CHECK(error_has(bad[i][0] ? "bad manager address" : "no manager address"));
    }
    setenv("LN_MANAGER", "robot1", 1);
    ln_client* c = NULL;
    LN_CHECK_EQ(ln_client_create(&c, "x", NULL), LN_EINVAL);
    LN_CHECK(error_has("bad manager address \"robot1\" (from LN_MANAGER)"));
    unsetenv("LN_MANAGER");

    char* argv[] = {"prog", "-ln_manager", NULL};
    ln_client_options o;
    ln_client_options_init(&o);
    o.argc = 2;
    o.argv = argv;
    LN_CHECK_EQ(ln_client_create(&c, "x", &o), LN_EINVAL);
    LN_CHECK(error_has("-ln_manager must be followed by HOST:PORT"));
}

static void test_no_address(void)
{
    unsetenv("LN_MANAGER");
    ln_client* c = NULL;
    LN_CHECK_EQ(ln_client_create(&c, "x", NULL), LN_EINVAL);
    LN_CHECK(error_has("ln_client_options.manager"));
    LN_CHECK(error_has("-ln_manager HOST:PORT"));
    LN_CHECK(error_has("LN_MANAGER"));
}

static void test_ipv6_address_parsed(void)
{
    ln_client_options o;
    ln_client_options_init(&o);
    o.manager = "[::1]:1";
    o.timeout = 5;
    ln_client* c = NULL;
    int rc = ln_client_create(&c, "x", &o); /* nothing listens there, if ::1 exists at all */
    LN_CHECK(rc != LN_OK && rc != LN_EINVAL);
    LN_CHECK(error_has("cannot connect to manager [::1]:1"));
}

static void test_bad_arguments(void)
{
    char long_name[LN_PROTO_MAX_STR + 2];
    memset(long_name, 'n', sizeof long_name - 1);
    long_name[sizeof long_name - 1] = '\0';
    ln_client_options o;
    ln_client_options_init(&o);
    o.manager = "127.0.0.1:1";
    ln_client* c = NULL;
    LN_CHECK_EQ(ln_client_create(&c, long_name, &o), LN_EINVAL);
    LN_CHECK(error_has("client name"));
    LN_CHECK_EQ(ln_client_create(&c, "bad\xff", &o), LN_EINVAL);
    o.timeout = NAN;
    LN_CHECK_EQ(ln_client_create(&c, "x", &o), LN_EINVAL);
    LN_CHECK_EQ(ln_client_create(NULL, "x", &o), LN_EINVAL);
    ln_client_options_init(NULL); /* harmless */
    LN_CHECK(o.argc == 0 && o.argv == NULL);
}

static void test_zero_timeout_means_default(void)
{
    struct fake f;
    fake_start(&f, script_welcome, 0);
    ln_client_options o = fake_options(&f);
    o.timeout = 0;
    ln_client* c = connect_ok("cam", &o);
    if (c != NULL)
        LN_CHECK(c->timeout == 10.0);
    ln_client_destroy(c);
    fake_stop(&f);
}

int main(void)
{
    LN_TEST_RUN(test_connection_refused);
    LN_TEST_RUN(test_address_sources);
    LN_TEST_RUN(test_program_name_override);
    LN_TEST_RUN(test_bad_addresses);
    LN_TEST_RUN(test_no_address);
    LN_TEST_RUN(test_ipv6_address_parsed);
    LN_TEST_RUN(test_bad_arguments);
    LN_TEST_RUN(test_zero_timeout_means_default);
    LN_TEST_EXIT();
}
