// arm_controller.cpp — the joint controller of the demo robot system (robot.lnc), in C++ through
// ln/ln.hpp: for every new sample of arm.state (robot/joint_state) it computes the torques of a
// PD law toward a moving target trajectory and publishes them on arm.command (robot/command,
// torque mode, stamped with the state's timestamp), and what it aimed at on arm.reference
// (robot/joint_state: target position and velocity, commanded torque, the state's cycle).
// The service arm.set_gains (robot/set_gains) changes the gains; it is answered between
// cycles, never blocking the loop, and unsafe gains are refused with ok=0 and the reason.
// One thread does it all in a waitset (ln/waitset.hpp, docs/waiting.md): it sleeps until a
// sample of arm.state, a request of the service group "control" or the 1 s status timer
// comes, and runs the callback attached to it.
// The gains the loop uses are the parameters kp and kd of the parameter block "gains"
// (ln/parameters.hpp, docs/parameters.md): their input is what arm.set_gains set, and
// `ln_manager param set arm.controller.gains kp [...]` overrides them, checked against the
// same limits, from the next cycle on (`param reset` hands them back to the service).
// A status line every second (the last state's time, the cycles of that second); SIGTERM or
// SIGINT ends it with exit status 0.
// Manager from -ln_manager or $LN_MANAGER.  Usage: arm_controller
#include <atomic>
#include <csignal>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include <ln/ln.hpp>
#include <ln/parameters.hpp>
#include <ln/waitset.hpp>

#include "robot_messages.hpp"

namespace {

constexpr int joints = 7;
constexpr double pi = 3.14159265358979323846;
constexpr double kp_max = 1000.0; // Nm/rad
constexpr double kd_max = 50.0;   // Nm s/rad
constexpr std::uint8_t mode_torque = 3;
constexpr double write_timeout = 0.0002; // s, a fifth of the sensor's period

volatile std::sig_atomic_t stop_signal = 0;
std::atomic<ln::waitset*> running{nullptr}; // the waitset the signal handler stops

extern "C" void on_signal(int sig)
{
    stop_signal = sig;
    if (ln::waitset* ws = running.load())
        ws->stop();
}

// Hands the waitset to the signal handler while it lives.
struct stopped_by_signals {
    explicit stopped_by_signals(ln::waitset& ws) { running = &ws; }
    ~stopped_by_signals() { running = nullptr; }
};

struct gains {
    double kp[joints];
    double kd[joints];
    std::string profile;
};

// Every joint swings around zero with its own amplitude and frequency.
void target(double t, double q[joints], double qd[joints])
{
    for (int j = 0; j < joints; j++) {
        double amplitude = 0.6 - 0.05 * j;               // rad
        double omega = 2.0 * pi * 0.2 * (1.0 + j / 7.0); // rad/s
        q[j] = amplitude * std::sin(omega * t);
        qd[j] = amplitude * omega * std::cos(omega * t);
    }
}

// Publishes msg unless the ring stays locked for longer than `timeout` (it is, for a moment,
// while the manager grows it for a new subscriber): then the sample is dropped, false.
template <typename T>
bool publish(ln::outport<T>& port, const T& msg, double timeout)
{
    try {
        port.write(msg, timeout);
        return true;
    } catch (const ln::error& e) {
        if (e.code() == LN_ETIMEOUT || e.code() == LN_EAGAIN)
            return false;
        throw;
    }
}

// Why these gains are unsafe, or "" when they are acceptable.
std::string check(const double kp[joints], const double kd[joints])
{
    char why[160] = "";
    for (int j = 0; j < joints && why[0] == '\0'; j++) {
        if (!(kp[j] > 0.0 && kp[j] <= kp_max)) // also refuses NaN
            std::snprintf(why, sizeof why, "kp[%d] = %g Nm/rad is outside (0, %g]", j, kp[j],
                          kp_max);
        else if (!(kd[j] >= 0.0 && kd[j] <= kd_max))
            std::snprintf(why, sizeof why, "kd[%d] = %g Nm s/rad is outside [0, %g]", j, kd[j],
                          kd_max);
    }
    return why;
}

} // namespace

int main(int argc, char** argv)
{
    struct sigaction sa;
    std::memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGTERM, &sa, nullptr);
    sigaction(SIGINT, &sa, nullptr);

    // Moderate gains until the supervisor sets its own.
    gains active{{50, 50, 30, 25, 12, 8, 4}, {10, 10, 6, 5, 2.5, 1.6, 0.8}, "default"};
    double kp[joints], kd[joints]; // what the loop uses: the parameters' outputs
    unsigned long accepted = 0, refused = 0;
    try {
        ln::client clnt("arm_controller", argc, argv);
        // The gains as parameters: input = the service's gains, checked like them.
        ln::parameters::parameter_block params(clnt, "gains");
        params.set_validator([](const std::string& name, const void* value) -> std::string {
            double v[joints];
            std::memcpy(v, value, sizeof v);
            for (int j = 0; j < joints; j++)
                if (name == "kp" && !(v[j] > 0.0))
                    return "kp[" + std::to_string(j) + "] must be above 0 Nm/rad";
            return "";
        });
        params.register_parameters(
            ln::parameters::port_description{"kp", "stiffness per joint (Nm/rad)", &active.kp, &kp,
                                             0.0, kp_max},
            ln::parameters::port_description{"kd", "damping per joint (Nm s/rad)", &active.kd, &kd,
                                             0.0, kd_max});
        params.update();
        auto state_in = clnt.subscribe<robot::joint_state_t>("arm.state"); // latest mode
        auto command_out = clnt.publish<robot::command_t>("arm.command");
        auto reference_out = clnt.publish<robot::joint_state_t>("arm.reference");
        using call_t = ln::service_provider<robot::set_gains_t>::call;
        std::string answer; // the response's message points into it while it is sent
        auto provider = clnt.provide_service<robot::set_gains_t>(
            "arm.set_gains",
            [&](call_t& c) {
                gains wanted;
                std::memcpy(wanted.kp, c.req.kp, sizeof wanted.kp); // packed: copy out
                std::memcpy(wanted.kd, c.req.kd, sizeof wanted.kd);
                if (c.req.profile_name != nullptr)
                    wanted.profile.assign(c.req.profile_name, c.req.profile_name_len);
                answer = check(wanted.kp, wanted.kd);
                c.resp.ok = answer.empty();
                c.resp.message_len = static_cast<std::uint32_t>(answer.size());
                c.resp.message = answer.data();
                if (answer.empty()) {
                    active = wanted; // used from the next cycle on
                    accepted++;
                } else {
                    refused++;
                }
                std::printf("gains '%s' %s%s\n", wanted.profile.c_str(),
                            answer.empty() ? "accepted" : "refused: ", answer.c_str());
                std::fflush(stdout);
                c.respond();
            },
            "control"); // registered last: once it is there, every port is ready
        std::printf("following arm.state, serving arm.set_gains\n");
        std::fflush(stdout);

        robot::joint_state_t state{};
        robot::command_t command{};
        robot::joint_state_t reference{};
        command.mode = mode_torque;
        unsigned long cycles = 0, cycles_in_second = 0, skipped = 0, dropped = 0;
        std::uint32_t last_cycle = 0;
        ln::waitset ws;
        // A cycle per new state (latest mode: the newest one, if several came meanwhile).
        auto cycle = ws.on_data(state_in, [&](ln::inport<robot::joint_state_t>& in) {
            if (!in.read(state, 0.0))
                return;
            if (params.update() > 0) { // an override came (or went): from this cycle on
                std::printf("parameters: kp[0] %g (%s), kd[0] %g (%s)\n", kp[0],
                            params.changed("kp") ? "changed" : "same", kd[0],
                            params.changed("kd") ? "changed" : "same");
                std::fflush(stdout);
            }
            double t = state.timestamp;
            double q_target[joints], qd_target[joints];
            target(t, q_target, qd_target);
            for (int j = 0; j < joints; j++) {
                double q = state.position[j], qd = state.velocity[j];
                command.target[j] = kp[j] * (q_target[j] - q) + kd[j] * (qd_target[j] - qd);
                reference.position[j] = q_target[j];
                reference.velocity[j] = qd_target[j];
                reference.effort[j] = command.target[j];
            }
            command.timestamp = t;
            reference.timestamp = t;
            reference.cycle = state.cycle;
            dropped += !publish(command_out, command, write_timeout);
            dropped += !publish(reference_out, reference, write_timeout);
            if (last_cycle != 0 && state.cycle > last_cycle + 1)
                skipped += state.cycle - last_cycle - 1; // latest mode: we fell behind
            last_cycle = state.cycle;
            cycles++;
            cycles_in_second++;
        });
        // Service calls between cycles: the waitset handles the group's pending requests.
        auto service = ws.on_requests(clnt, "control");
        auto status = ws.every(1.0, [&] {
            std::string extra;
            if (dropped > 0)
                extra = ", " + std::to_string(dropped) + " samples dropped";
            std::printf("t=%.0f s: %lu cycles in the last second, %lu skipped in all%s, gains "
                        "'%s' (kp[0] %g, kd[0] %g)\n",
                        state.timestamp, cycles_in_second, skipped, extra.c_str(),
                        active.profile.c_str(), kp[0], kd[0]);
            std::fflush(stdout);
            cycles_in_second = 0;
        });
        stopped_by_signals armed(ws);
        if (!stop_signal) // else it came before the handler could stop the waitset
            ws.spin();
        std::printf("stopped by %s after %lu cycles (%lu skipped, %lu samples dropped); %lu "
                    "gain settings accepted, %lu refused\n",
                    stop_signal == SIGINT ? "SIGINT" : "SIGTERM", cycles, skipped, dropped,
                    accepted, refused);
    } catch (const ln::error& e) {
        std::fprintf(stderr, "arm_controller: %s\n", e.what());
        return 1;
    }
    return 0;
}
