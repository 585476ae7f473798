//! arm_controller (Rust) — the joint controller of rust_robot.lnc, the Rust twin of
//! examples/robot/arm_controller.cpp: a 1 kHz loop on absolute deadlines (the next deadline
//! is the previous one plus the period, so the rate does not drift with the work) reads the
//! newest arm.state (robot/joint_state), computes the torques of a PD law toward a moving
//! target and publishes them on arm.command (robot/command, torque mode) and what it aimed
//! at on arm.reference (robot/joint_state, the state's cycle).  It provides arm.set_gains
//! (robot/set_gains), answered between cycles in the loop's thread, never blocking it;
//! unsafe gains are refused with ok=0 and the reason.  A status line every second; SIGTERM
//! or SIGINT ends it with exit status 0.  Manager from -ln_manager or $LN_MANAGER.
//!
//!     arm_controller [--rate HZ]

use std::process::ExitCode;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use links_and_nodes::{
    Client, Error, Mode, ProviderOptions, PublisherOptions, ServiceError, StopSignal,
};
use links_and_nodes_examples::msg::robot::{
    Command, JointState, SetGains, SetGainsRequest, SetGainsResponse,
};
use links_and_nodes_examples::{profile, JOINTS};

const KP_MAX: f64 = 1000.0; // Nm/rad
const KD_MAX: f64 = 50.0; // Nm s/rad
const MODE_TORQUE: u8 = 3;
const GROUP: &str = "control";

/// The gains the loop uses and the name of their profile.
#[derive(Clone)]
struct Gains {
    kp: [f64; JOINTS],
    kd: [f64; JOINTS],
    profile: String,
}

/// Why these gains are unsafe, `None` when they are acceptable (NaN is refused too).
fn check(kp: &[f64; JOINTS], kd: &[f64; JOINTS]) -> Option<String> {
    for j in 0..JOINTS {
        if !(kp[j] > 0.0 && kp[j] <= KP_MAX) {
            return Some(format!(
                "kp[{j}] = {} Nm/rad is outside (0, {KP_MAX}]",
                kp[j]
            ));
        }
        if !(kd[j] >= 0.0 && kd[j] <= KD_MAX) {
            return Some(format!(
                "kd[{j}] = {} Nm s/rad is outside [0, {KD_MAX}]",
                kd[j]
            ));
        }
    }
    None
}

/// Every joint swings around zero with its own amplitude and frequency (as the C++ one).
fn target(t: f64) -> ([f64; JOINTS], [f64; JOINTS]) {
    let (mut q, mut qd) = ([0.0; JOINTS], [0.0; JOINTS]);
    for j in 0..JOINTS {
        let amplitude = 0.6 - 0.05 * j as f64;
        let omega = 2.0 * std::f64::consts::PI * 0.2 * (1.0 + j as f64 / 7.0);
        q[j] = amplitude * (omega * t).sin();
        qd[j] = amplitude * omega * (omega * t).cos();
    }
    (q, qd)
}

/// The answer to one arm.set_gains request; accepted gains replace `gains`.
fn set_gains(gains: &Mutex<Gains>, req: SetGainsRequest) -> SetGainsResponse {
    let (kp, kd) = (req.kp, req.kd);
    let refusal = check(&kp, &kd);
    match &refusal {
        None => {
            let mut active = gains.lock().unwrap_or_else(|e| e.into_inner());
            *active = Gains {
                kp,
                kd,
                profile: req.profile_name.clone(),
            };
            println!("gains '{}' accepted", req.profile_name);
        }
        Some(why) => println!("gains '{}' refused: {why}", req.profile_name),
    }
    SetGainsResponse {
        ok: u8::from(refusal.is_none()),
        message: refusal.unwrap_or_default(),
    }
}

/// A sample that could not be written within the publisher's timeout (the manager grows the
/// ring for a new subscriber for a moment) is dropped: Ok(false).
fn published(result: links_and_nodes::Result<()>) -> links_and_nodes::Result<bool> {
    match result {
        Ok(()) => Ok(true),
        Err(Error::ETIMEOUT(_) | Error::EAGAIN(_)) => Ok(false),
        Err(e) => Err(e),
    }
}

fn parse_rate() -> Result<f64, String> {
    let args: Vec<String> = std::env::args().collect();
    let mut rate = 1000.0;
    let mut i = 1;
    while i < args.len() {
        match args[i].as_str() {
            "--rate" => {
                let value = args.get(i + 1).ok_or("--rate needs a value")?;
                rate = value
                    .parse()
                    .map_err(|_| format!("--rate: not a number: {value}"))?;
                i += 2;
            }
            "-ln_manager" => i += 2, // the client reads it itself
            other => return Err(format!("unknown argument {other}")),
        }
    }
    if !(rate > 0.0 && rate <= 10_000.0) {
        return Err(format!("--rate {rate} is outside (0, 10000] Hz"));
    }
    Ok(rate)
}

fn run(rate: f64, stop: StopSignal) -> links_and_nodes::Result<()> {
    let client = Client::new("arm_controller")?;
    let (kp, kd) = profile("soft").expect("a built-in profile");
    let gains = Arc::new(Mutex::new(Gains {
        kp,
        kd,
        profile: "default".into(),
    }));
    let mut state_in = client.subscribe::<JointState>("arm.state", Mode::Latest)?;
    let options = PublisherOptions {
        timeout: 0.2 / rate,
        ..PublisherOptions::default()
    };
    let mut command_out = client.publish::<Command>("arm.command", options)?;
    let mut reference_out = client.publish::<JointState>("arm.reference", options)?;
    let handler_gains = Arc::clone(&gains);
    let _provider = client.provide_with::<SetGains, _>(
        "arm.set_gains",
        &ProviderOptions {
            group: Some(GROUP.into()),
            ..ProviderOptions::default()
        },
        move |req| -> Result<SetGainsResponse, ServiceError> { Ok(set_gains(&handler_gains, req)) },
    )?; // registered last: once it is there, every port is ready
    println!("following arm.state at {rate} Hz, serving arm.set_gains");

    let period = Duration::from_secs_f64(1.0 / rate);
    let mut deadline = Instant::now();
    let (mut cycles, mut in_second, mut late, mut dropped, mut stale) =
        (0u64, 0u64, 0u64, 0u64, 0u64);
    let mut last_cycle = None;
    let mut next_status = Instant::now() + Duration::from_secs(1);
    let mut command = Command {
        mode: MODE_TORQUE,
        ..Command::default()
    };
    while !stop.requested() {
        if let Some(sample) = state_in.read(0.0)? {
            let state = *sample.data();
            let active = gains.lock().unwrap_or_else(|e| e.into_inner()).clone();
            let (position, velocity) = (state.position, state.velocity);
            let (q_target, qd_target) = target(state.timestamp);
            let mut torque = [0.0; JOINTS];
            for j in 0..JOINTS {
                torque[j] = active.kp[j] * (q_target[j] - position[j])
                    + active.kd[j] * (qd_target[j] - velocity[j]);
            }
            command.timestamp = state.timestamp;
            command.target = torque;
            let reference = JointState {
                timestamp: state.timestamp,
                cycle: state.cycle,
                position: q_target,
                velocity: qd_target,
                effort: torque,
            };
            dropped += u64::from(!published(command_out.write(&command))?);
            dropped += u64::from(!published(reference_out.write(&reference))?);
            last_cycle = Some(state.cycle);
            cycles += 1;
            in_second += 1;
        } else {
            stale += 1; // no new state this period: the sensor's clock and ours drift apart
        }
        // Service calls between cycles: handle what is pending, never wait.
        match client.handle_service_requests(Some(GROUP), 0.0) {
            Ok(_) | Err(Error::EINTR(_)) => {}
            Err(e) => return Err(e),
        }
        let now = Instant::now();
        if now >= next_status {
            let active = gains.lock().unwrap_or_else(|e| e.into_inner()).clone();
            println!(
                "cycle {}: {in_second} cycles in the last second, {late} late and {stale} without \
                 a new state in all, {dropped} samples dropped, gains '{}' (kp[0] {}, kd[0] {})",
                last_cycle.unwrap_or(0),
                active.profile,
                active.kp[0],
                active.kd[0]
            );
            in_second = 0;
            next_status += Duration::from_secs(1);
        }
        deadline += period;
        match deadline.checked_duration_since(Instant::now()) {
            Some(wait) => std::thread::sleep(wait),
            None => {
                late += 1; // overran the period: start again from now, do not catch up
                deadline = Instant::now();
            }
        }
    }
    println!(
        "stopped by {} after {cycles} cycles ({late} late, {dropped} samples dropped)",
        stop.name().unwrap_or("request")
    );
    Ok(())
}

fn main() -> ExitCode {
    let rate = match parse_rate() {
        Ok(rate) => rate,
        Err(why) => {
            eprintln!("arm_controller: {why}\nusage: arm_controller [--rate HZ]");
            return ExitCode::from(2);
        }
    };
    let stop = match StopSignal::install() {
        Ok(stop) => stop,
        Err(e) => {
            eprintln!("arm_controller: {e}");
            return ExitCode::FAILURE;
        }
    };
    match run(rate, stop) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("arm_controller: {e}");
            ExitCode::FAILURE
        }
    }
}
