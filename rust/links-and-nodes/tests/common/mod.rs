//! What the integration tests share: a manager of their own per test (an unused port, a
//! unique instance, its runtime files in a temporary directory removed afterwards), clients
//! of it, its command-line tools, and the hand-written message types of tests/md.

#![allow(dead_code)]

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use links_and_nodes::{Client, ClientOptions, Message};

/// md rust_test/counter (tests/md/rust_test/counter).
#[repr(C, packed)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Counter {
    pub count: u64,
    pub value: f64,
}

// SAFETY: the packed fields of md rust_test/counter in order; any bits are valid.  The hash
// is checked against ln_generate by md_types.rs.
unsafe impl Message for Counter {
    const MD_NAME: &'static str = "rust_test/counter";
    const LAYOUT_HASH: u64 = 0x1bed_e26f_5759_83fc;
}

/// md rust_test/counter_other: another layout (uint32_t count).
#[repr(C, packed)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CounterOther {
    pub count: u32,
    pub value: f64,
}

// SAFETY: as for Counter.
unsafe impl Message for CounterOther {
    const MD_NAME: &'static str = "rust_test/counter_other";
    const LAYOUT_HASH: u64 = 0xd7b2_2318_428b_7e9f;
}

pub fn checkout() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The Python with links_and_nodes: $LN_PYTHON, else the checkout's .venv, else python3.
pub fn python() -> PathBuf {
    if let Some(p) = std::env::var_os("LN_PYTHON") {
        return PathBuf::from(p);
    }
    let venv = checkout().join(".venv/bin/python");
    if venv.exists() {
        venv
    } else {
        PathBuf::from("python3")
    }
}

static NEXT: AtomicUsize = AtomicUsize::new(0);

/// A manager process of one test; killed and its directory removed on drop.
pub struct Manager {
    child: Child,
    pub address: String,
    pub dir: PathBuf,
    instance: String,
}

/// Where libln puts a client's runtime files (service sockets) of `instance` without
/// LN_RUNTIME_DIR (naming.c): $XDG_RUNTIME_DIR/ln/INSTANCE, else /tmp/ln-UID/INSTANCE.
fn client_runtime_dir(instance: &str) -> PathBuf {
    use std::os::unix::fs::MetadataExt;
    match std::env::var_os("XDG_RUNTIME_DIR").filter(|d| !d.is_empty()) {
        Some(xdg) => Path::new(&xdg).join("ln").join(instance),
        None => {
            let uid = fs::metadata("/proc/self").map(|m| m.uid()).unwrap_or(0);
            PathBuf::from(format!("/tmp/ln-{uid}")).join(instance)
        }
    }
}

impl Manager {
    pub fn start() -> Manager {
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let instance = format!("rust-test-{}-{n}", std::process::id());
        let dir = std::env::temp_dir().join(format!("ln-{instance}"));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        let log = dir.join("manager.log");
        let child = Command::new(python())
            .args([
                "-m",
                "links_and_nodes.manager",
                "--port",
                "0",
                "--no-console",
            ])
            .args(["--instance", &instance])
            .env("LN_RUNTIME_DIR", dir.join("run"))
            .stdin(Stdio::null())
            .stdout(fs::File::create(&log).unwrap())
            .stderr(Stdio::from(
                fs::File::create(dir.join("manager.err")).unwrap(),
            ))
            .spawn()
            .expect("cannot start the manager");
        let mut manager = Manager {
            child,
            address: String::new(),
            dir,
            instance,
        };
        let deadline = Instant::now() + Duration::from_secs(60);
        while Instant::now() < deadline {
            let text = fs::read_to_string(&log).unwrap_or_default();
            if let Some(line) = text.lines().find(|l| l.contains(" listening on ")) {
                manager.address = line.rsplit(' ').next().unwrap().trim().to_string();
                return manager;
            }
            if let Ok(Some(status)) = manager.child.try_wait() {
                panic!("manager exited ({status}): {}", manager.output());
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        panic!("manager did not start: {}", manager.output());
    }

    pub fn output(&self) -> String {
        let log = fs::read_to_string(self.dir.join("manager.log")).unwrap_or_default();
        let err = fs::read_to_string(self.dir.join("manager.err")).unwrap_or_default();
        format!("{log}{err}")
    }

    pub fn options(&self) -> ClientOptions {
        ClientOptions {
            manager: Some(self.address.clone()),
            argv: Some(Vec::new()),
            timeout: Some(10.0),
            no_reconnect: true,
        }
    }

    pub fn client(&self, name: &str) -> Client {
        Client::with_options(name, &self.options()).expect("client")
    }

    /// `ln_manager ARGS --manager ADDRESS` (e.g. `param set ...`).
    pub fn tool(&self, args: &[&str]) -> Output {
        Command::new(python())
            .args(["-m", "links_and_nodes.manager"])
            .args(args)
            .args(["--manager", &self.address])
            .env("LN_RUNTIME_DIR", self.dir.join("run"))
            .output()
            .expect("cannot run ln_manager")
    }
}

impl Drop for Manager {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = fs::remove_dir_all(&self.dir);
        let _ = fs::remove_dir_all(client_runtime_dir(&self.instance));
    }
}

/// Polls `f` every 10 ms until it is true or `seconds` passed; whether it became true.
pub fn eventually(seconds: u64, mut f: impl FnMut() -> bool) -> bool {
    let deadline = Instant::now() + Duration::from_secs(seconds);
    while Instant::now() < deadline {
        if f() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    f()
}
