//! set_gains (Rust) — a service caller: asks the arm controller for a gain profile through
//! arm.set_gains (robot/set_gains) and prints its answer, "arm.set_gains 'NAME': accepted" or
//! "... refused (why)".  Exit status 0 when the controller answered (accepted or refused), 1
//! when the call failed (no provider within the timeout, the provider died), 2 on usage.
//! Manager from -ln_manager or $LN_MANAGER.
//!
//!     set_gains soft|stiff|unsafe [--timeout SECONDS]

use std::process::ExitCode;

use links_and_nodes::Client;
use links_and_nodes_examples::msg::robot::{SetGains, SetGainsRequest};
use links_and_nodes_examples::profile;

const USAGE: &str = "usage: set_gains soft|stiff|unsafe [--timeout SECONDS]";

fn parse() -> Result<(String, f64), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (mut name, mut timeout) = (None, 5.0);
    let mut i = 0;
    while i < args.len() {
        match args[i].as_str() {
            "--timeout" => {
                let value = args.get(i + 1).ok_or("--timeout needs a value")?;
                timeout = value
                    .parse()
                    .map_err(|_| format!("--timeout: not a number: {value}"))?;
                i += 2;
            }
            "-ln_manager" => i += 2, // the client reads it itself
            other if name.is_none() && !other.starts_with('-') => {
                name = Some(other.to_string());
                i += 1;
            }
            other => return Err(format!("unexpected argument {other}")),
        }
    }
    name.map(|n| (n, timeout))
        .ok_or_else(|| "which profile?".to_string())
}

fn main() -> ExitCode {
    let (name, timeout) = match parse() {
        Ok(parsed) => parsed,
        Err(why) => {
            eprintln!("set_gains: {why}\n{USAGE}");
            return ExitCode::from(2);
        }
    };
    let Some((kp, kd)) = profile(&name) else {
        eprintln!("set_gains: unknown profile '{name}'\n{USAGE}");
        return ExitCode::from(2);
    };
    let call = || -> links_and_nodes::Result<_> {
        let client = Client::new("set_gains")?;
        let service = client.service::<SetGains>("arm.set_gains")?;
        let request = SetGainsRequest {
            kp,
            kd,
            profile_name: name.clone(),
        };
        service.call(&request, timeout)
    };
    match call() {
        Ok(resp) if resp.ok != 0 => {
            println!("arm.set_gains '{name}': accepted");
            ExitCode::SUCCESS
        }
        Ok(resp) => {
            println!("arm.set_gains '{name}': refused ({})", resp.message);
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("set_gains: arm.set_gains: {e}");
            ExitCode::FAILURE
        }
    }
}
