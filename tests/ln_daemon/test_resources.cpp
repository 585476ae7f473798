// Unit tests of the resource sampler (resources.hpp): each /proc parser on the fixture tree
// tests/fixtures/proc and on damaged text (an error naming the file, never a crash or a read
// past the text), the Sampler's rates over two rounds of a tree it is given, and one real
// sample of this process and host.
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/stat.h>
#include <unistd.h>
#include <vector>

#include "daemon_test.hpp"
#include "resources.hpp"

using namespace lnd;
using namespace lnd::res;

namespace {

std::string fixture(const std::string &name)
{
    std::ifstream in(std::string(LN_PROC_FIXTURES) + "/" + name);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

void write_file(const std::string &path, const std::string &text) { std::ofstream(path) << text; }

void test_pid_stat()
{
    PidStat st;
    LN_CHECK(!parse_pid_stat(fixture("4242/stat"), st).failed());
    LN_CHECK_EQ(st.ticks, 300u); // utime 250 + stime 50
    LN_CHECK_EQ(st.threads, 7u);
    LN_CHECK_EQ(st.rss_pages, 25600u);
}

void test_pid_status()
{
    PidStatus s;
    LN_CHECK(!parse_pid_status(fixture("4242/status"), s).failed());
    LN_CHECK_EQ(s.rss_bytes, 102400u * 1024);
    LN_CHECK_EQ(s.voluntary, 150u);
    LN_CHECK_EQ(s.involuntary, 12u);
}

void test_host_files()
{
    CpuTicks all;
    std::vector<CpuTicks> cpus;
    LN_CHECK(!parse_proc_stat(fixture("stat"), all, cpus).failed());
    LN_CHECK_EQ(cpus.size(), 2u);
    LN_CHECK_EQ(all.total, 4705u + 150 + 1120 + 16250 + 520 + 30);
    LN_CHECK_EQ(all.busy, all.total - 16250 - 520);
    MemInfo m;
    LN_CHECK(!parse_meminfo(fixture("meminfo"), m).failed());
    LN_CHECK_EQ(m.total, 16318484ull * 1024);
    LN_CHECK_EQ(m.available, 8159242ull * 1024);
    LN_CHECK_EQ(m.swap_free, 1048574ull * 1024);
    std::vector<NetBytes> net;
    LN_CHECK(!parse_net_dev(fixture("net/dev"), net).failed());
    LN_CHECK_EQ(net.size(), 2u);
    CHECK_STR(net[1].interface, "eth0");
    LN_CHECK_EQ(net[1].rx, 9876543210ull);
    LN_CHECK_EQ(net[1].tx, 1234567u);
    LoadAvg l;
    LN_CHECK(!parse_loadavg(fixture("loadavg"), l).failed());
    LN_CHECK(l.one > 0.519 && l.one < 0.521);
    LN_CHECK(l.fifteen > 0.589 && l.fifteen < 0.591);
}

// Every prefix of every fixture, and some damaged texts: an error or a result, nothing else
// (run under the sanitizers by `scons check sanitize=...`).
void test_damaged()
{
    std::string text;
    PidStat st;
    PidStatus ps;
    LN_CHECK(parse_pid_stat("4242 my prog S 1", st).failed());
    LN_CHECK(parse_pid_stat("4242 (x) S 1 2 3", st).failed());
    LN_CHECK(passed(parse_pid_stat("", st), text) == false);
    CHECK_STR(text, "stat: cannot read the command name");
    LN_CHECK(!passed(parse_pid_status("Name:\tx\nVmRSS:\tlots kB\n", ps), text));
    CHECK_STR(text, "status: cannot read VmRSS");
    LN_CHECK(parse_pid_status("Name:\tx\n", ps).failed());
    CpuTicks all;
    std::vector<CpuTicks> cpus;
    LN_CHECK(parse_proc_stat("intr 1 2 3\n", all, cpus).failed());
    LN_CHECK(parse_proc_stat("cpu  1 2\n", all, cpus).failed());
    LN_CHECK(parse_proc_stat("cpu  99999999999999999999999 1 1 1\n", all, cpus).failed());
    MemInfo m;
    LN_CHECK(parse_meminfo("MemFree: 1 kB\n", m).failed());
    LN_CHECK(parse_meminfo("MemTotal: 99999999999999999999 kB\n", m).failed());
    std::vector<NetBytes> net;
    LN_CHECK(parse_net_dev(" eth0: 1 2 3\n", net).failed());
    LN_CHECK(parse_net_dev(" : 1 2 3 4 5 6 7 8 9\n", net).failed());
    LoadAvg l;
    LN_CHECK(parse_loadavg("high\n", l).failed());
    for (const char *name : {"4242/stat", "4242/status", "stat", "meminfo", "net/dev", "loadavg"}) {
        std::string whole = fixture(name);
        for (size_t n = 0; n < whole.size(); ++n) {
            std::string part = whole.substr(0, n); // a copy: sanitizers see reads beyond it
            (void)parse_pid_stat(part, st);
            (void)parse_pid_status(part, ps);
            (void)parse_proc_stat(part, all, cpus);
            (void)parse_meminfo(part, m);
            (void)parse_net_dev(part, net);
            (void)parse_loadavg(part, l);
        }
    }
}

// Two rounds over a tree of our own: CPU % and byte rates from the differences.
void test_sampler_rates()
{
    char dir[] = "/tmp/ln_resources_XXXXXX";
    LN_CHECK(::mkdtemp(dir) != nullptr);
    std::string root = dir;
    ::mkdir((root + "/net").c_str(), 0700);
    ::mkdir((root + "/7").c_str(), 0700);
    ::mkdir((root + "/7/fd").c_str(), 0700);
    write_file(root + "/7/fd/0", "");
    write_file(root + "/loadavg", fixture("loadavg"));
    write_file(root + "/meminfo", fixture("meminfo"));
    write_file(root + "/7/status", fixture("4242/status"));
    auto round = [&](unsigned ticks, unsigned idle, unsigned long rx) {
        write_file(root + "/stat", "cpu  " + std::to_string(ticks) + " 0 0 " +
                                       std::to_string(idle) + " 0\ncpu0 " + std::to_string(ticks) +
                                       " 0 0 " + std::to_string(idle) + " 0\n");
        write_file(root + "/net/dev", "h|\nh|\n eth0: " + std::to_string(rx) + " 0 0 0 0 0 0 0 " +
                                          std::to_string(rx / 2) + " 0 0 0 0 0 0 0\n");
        write_file(root + "/7/stat", "7 (p) R 1 7 7 0 -1 0 0 0 0 0 " + std::to_string(ticks) +
                                         " 0 0 0 20 0 1 0 1 1 1 0\n");
    };
    Sampler s(root, 100);
    wire::EvResources host;
    wire::ProcessResources p;
    round(100, 100, 1000);
    LN_CHECK(!s.sample_host(10.0, host).failed());
    LN_CHECK(!s.sample_process(7, 10.0, p).failed());
    LN_CHECK(p.cpu < 0); // no previous sample
    LN_CHECK_EQ(p.fds, 1u);
    LN_CHECK_EQ(host.nets.size(), 1u);
    round(150, 150, 3000); // 50 ticks of 100 per second in 0.5 s: one core busy
    LN_CHECK(!s.sample_host(10.5, host).failed());
    LN_CHECK(!s.sample_process(7, 10.5, p).failed());
    LN_CHECK(p.cpu > 99.9 && p.cpu < 100.1);
    LN_CHECK(host.cpu > 49.9 && host.cpu < 50.1);
    LN_CHECK_EQ(host.cpus.size(), 1u);
    LN_CHECK(host.nets[0].rx > 3999 && host.nets[0].rx < 4001);
    LN_CHECK(host.nets[0].tx > 1999 && host.nets[0].tx < 2001);
    LN_CHECK_EQ(p.rss, 102400u * 1024);
    write_file(root + "/7/stat", "7 (p) R garbage\n"); // damaged: an error, no figures
    std::string text;
    LN_CHECK(!passed(s.sample_process(7, 11.0, p), text));
    CHECK_STR(text, "stat: cannot read field 4");
    LN_CHECK(s.sample_process(8, 11.0, p).failed()); // no such process
    write_file(root + "/meminfo", "nothing\n");
    LN_CHECK(s.sample_host(11.0, host).failed());
    std::string cmd = "rm -rf " + root;
    LN_CHECK(std::system(cmd.c_str()) == 0);
}

void test_real_proc()
{
    Sampler s;
    wire::EvResources host;
    wire::ProcessResources p;
    LN_CHECK(!s.sample_host(1.0, host).failed());
    LN_CHECK(!host.cpus.empty());
    LN_CHECK(host.mem_total > 0 && host.mem_available <= host.mem_total);
    LN_CHECK(!s.sample_process(::getpid(), 1.0, p).failed());
    LN_CHECK(p.threads >= 1);
    LN_CHECK(p.rss > 0);
    LN_CHECK(p.fds >= 3);
}

} // namespace

int main()
{
    LN_TEST_RUN(test_pid_stat);
    LN_TEST_RUN(test_pid_status);
    LN_TEST_RUN(test_host_files);
    LN_TEST_RUN(test_damaged);
    LN_TEST_RUN(test_sampler_rates);
    LN_TEST_RUN(test_real_proc);
    LN_TEST_EXIT();
}
