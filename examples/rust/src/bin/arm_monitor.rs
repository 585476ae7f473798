//! arm_monitor (Rust) — a subscriber of rust_robot.lnc: follows every sample of arm.state
//! (robot/joint_state, queued: none is missed while it keeps up) and prints once a second how
//! many came, the gaps in the sensor's cycle counter, the publish-to-read latency and the
//! largest joint torque.  Ready once it prints "monitoring arm.state".  SIGTERM or SIGINT
//! ends it with exit status 0.  Manager from -ln_manager or $LN_MANAGER.
//!
//!     arm_monitor

use std::process::ExitCode;
use std::time::{Instant, SystemTime, UNIX_EPOCH};

use links_and_nodes::{Client, Mode, StopSignal};
use links_and_nodes_examples::msg::robot::JointState;

/// One second of statistics.
#[derive(Default)]
struct Second {
    samples: u64,
    gaps: u64,
    latency_max_us: f64,
    effort_max: f64,
}

fn now_ns() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as i64)
}

fn run(stop: StopSignal) -> links_and_nodes::Result<()> {
    let client = Client::new("arm_monitor")?;
    let mut states = client.subscribe::<JointState>("arm.state", Mode::Queued(256))?;
    println!("monitoring arm.state");
    let mut second = Second::default();
    let mut last_cycle: Option<u32> = None;
    let mut next = Instant::now() + std::time::Duration::from_secs(1);
    let mut total = 0u64;
    while !stop.requested() {
        if let Some(sample) = states.read(0.05)? {
            let latency_us = (now_ns() - sample.timestamp_ns()) as f64 / 1e3;
            let state = *sample.data();
            let effort = state.effort;
            let cycle = state.cycle;
            if let Some(last) = last_cycle {
                second.gaps += u64::from(cycle.wrapping_sub(last).saturating_sub(1));
            }
            last_cycle = Some(cycle);
            second.samples += 1;
            second.latency_max_us = second.latency_max_us.max(latency_us);
            second.effort_max = effort.iter().fold(second.effort_max, |m, e| m.max(e.abs()));
        }
        if Instant::now() >= next {
            total += second.samples;
            println!(
                "arm.state: {} samples, {} missed cycles, latency max {:.0} us, torque max {:.1} Nm",
                second.samples, second.gaps, second.latency_max_us, second.effort_max
            );
            second = Second::default();
            next += std::time::Duration::from_secs(1);
        }
    }
    println!(
        "stopped by {} after {total} samples",
        stop.name().unwrap_or("request")
    );
    Ok(())
}

fn main() -> ExitCode {
    let result = StopSignal::install().and_then(run);
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("arm_monitor: {e}");
            ExitCode::FAILURE
        }
    }
}
