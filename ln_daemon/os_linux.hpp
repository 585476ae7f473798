// The real Os: a keeper process per supervised process (a child subreaper that starts it,
// reports its start and exit, and lives until its whole tree is gone), /proc scans to
// signal that tree, waitpid and the clocks.
#pragma once

#include <sys/resource.h>

#include "os.hpp"

namespace lnd {

class LinuxOs final : public Os {
public:
    LinuxOs() noexcept; // raises the daemon's descriptor limit
    double monotonic() noexcept override;
    double wall() noexcept override;
    Outcome launch(const LaunchSpec &spec, Launched &out) override;
    int kill(pid_t pid, int sig) noexcept override;
    int kill_tree(pid_t keeper, int sig, pid_t skip_group) noexcept override;
    bool reap(pid_t &pid, int &status) noexcept override;

private:
    struct rlimit nofile_ = {}; // as the daemon found it; what children get
};

} // namespace lnd
