//! [`Client`]: one connection to the manager (`ln_client`), and the shared state every handle
//! of it (ports, parameter blocks, services) keeps alive with an `Arc`: a gate that makes a
//! use after `close()`/drop an `ECLOSED` error instead of a use of freed memory.

use std::any::Any;
use std::ffi::{c_char, CStr, CString};
use std::ptr;
use std::sync::atomic::{AtomicBool, AtomicPtr, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, RwLock, RwLockReadGuard};

use crate::error::{Detail, Error, Result};
use crate::{check, sys};

/// How to reach the manager; `Default` is what C's `ln_client_options_init` gives plus this
/// process's arguments: `-ln_manager HOST:PORT` in argv, then `$LN_MANAGER`.
#[derive(Debug, Clone, Default)]
pub struct ClientOptions {
    /// "HOST:PORT" or ":PORT"; `None`: `-ln_manager` of `argv`, then `$LN_MANAGER`.
    pub manager: Option<String>,
    /// Arguments searched for `-ln_manager HOST:PORT`; `None`: this process's arguments.
    pub argv: Option<Vec<String>>,
    /// Seconds for connecting and for each manager request; `None`: libln's default (10).
    pub timeout: Option<f64>,
    /// Do not reconnect after the manager went away (`LN_CLIENT_NO_RECONNECT`).
    pub no_reconnect: bool,
}

/// What a client's handles share.  `raw` is destroyed once: by `close()` when no operation is
/// in progress, else by the drop of the last `Arc` (the last handle).
pub(crate) struct Shared {
    raw: AtomicPtr<sys::ln_client>,
    closed: AtomicBool,
    /// Read-held around every libln call on the client or its handles; `close()` write-holds
    /// it to destroy the client, so no call can run on freed memory.
    gate: RwLock<()>,
    /// ln.h: setup calls (create, publish, subscribe, unpublish, ...) one thread at a time.
    setup: Mutex<()>,
    name: String,
    /// Memory libln points into (parameter values) whose handle was dropped after the
    /// client closed: freed only after the client is destroyed.
    keep: Mutex<Vec<Box<dyn Any + Send>>>,
}

// SAFETY: ln.h allows the client's calls from any thread (setup calls serialized: `setup`);
// the pointer is only used under `gate`, which keeps it alive.
unsafe impl Send for Shared {}
// SAFETY: as above; every shared use goes through `gate` and `setup`.
unsafe impl Sync for Shared {}

/// Proof that the client is open for the duration of a libln call (holds the gate).
pub(crate) struct Open<'a> {
    _gate: RwLockReadGuard<'a, ()>,
    raw: *mut sys::ln_client,
}

impl Open<'_> {
    /// The client, valid while this guard lives.
    pub(crate) fn raw(&self) -> *mut sys::ln_client {
        self.raw
    }
}

impl Shared {
    /// Opens the gate for one call: `ECLOSED` after `close()` or the drop of the [`Client`].
    pub(crate) fn enter(&self) -> Result<Open<'_>> {
        let gate = self.gate.read().unwrap_or_else(|e| e.into_inner());
        let raw = self.raw.load(Ordering::Acquire);
        if self.closed.load(Ordering::Acquire) || raw.is_null() {
            return Err(Error::ECLOSED(Detail::none()));
        }
        Ok(Open { _gate: gate, raw })
    }

    /// `enter()` plus the setup lock, for ln.h's setup calls.
    pub(crate) fn enter_setup(&self) -> Result<(Open<'_>, MutexGuard<'_, ()>)> {
        let open = self.enter()?;
        let setup = self.setup.lock().unwrap_or_else(|e| e.into_inner());
        Ok((open, setup))
    }

    /// Whether the client was closed (its handles must not call libln any more).
    #[allow(dead_code)]
    pub(crate) fn is_closed(&self) -> bool {
        self.closed.load(Ordering::Acquire)
    }

    /// Keeps `memory` until the client is destroyed (libln may still point into it).
    pub(crate) fn keep_until_destroyed(&self, memory: Box<dyn Any + Send>) {
        self.keep
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(memory);
    }

    fn close(&self) -> Result<()> {
        self.closed.store(true, Ordering::Release);
        // An operation in progress (possibly a loan or borrow on this very thread) holds the
        // gate: then the last handle's drop destroys the client, never a wait here.
        let Ok(_gate) = self.gate.try_write() else {
            return Ok(());
        };
        self.destroy()
    }

    fn destroy(&self) -> Result<()> {
        let raw = self.raw.swap(ptr::null_mut(), Ordering::AcqRel);
        if raw.is_null() {
            return Ok(());
        }
        // SAFETY: raw came from ln_client_create and is destroyed exactly once (swapped out).
        check(unsafe { sys::ln_client_destroy(raw) }).map(|_| ())
    }
}

impl Drop for Shared {
    fn drop(&mut self) {
        let _ = self.destroy();
    }
}

/// A client of the manager: the owner of its ports, parameter blocks and services.
///
/// Threads: `Send + Sync`.  Setup calls (publish, subscribe, parameter blocks, ...) from
/// several threads are serialized by the client, as ln.h requires.  Dropping the client (or
/// [`Client::close`]) closes it: from then on every handle of it returns `Error::ECLOSED`.
pub struct Client {
    shared: Arc<Shared>,
}

pub(crate) fn cstring(what: &str, s: &str) -> Result<CString> {
    CString::new(s).map_err(|_| {
        Error::with_detail(
            sys::LN_EINVAL,
            format!("{what} {s:?} contains a NUL byte").into(),
        )
    })
}

impl Client {
    /// Connects as `name` to the manager named by `-ln_manager HOST:PORT` in this process's
    /// arguments, else `$LN_MANAGER` (as the C and Python clients do).
    pub fn new(name: &str) -> Result<Client> {
        Client::with_options(name, &ClientOptions::default())
    }

    /// Connects as `name` with explicit options.
    pub fn with_options(name: &str, options: &ClientOptions) -> Result<Client> {
        let c_name = cstring("client name", name)?;
        let manager = match &options.manager {
            Some(m) => Some(cstring("manager address", m)?),
            None => None,
        };
        let args: Vec<String> = match &options.argv {
            Some(a) => a.clone(),
            None => std::env::args_os()
                .map(|a| a.to_string_lossy().into_owned())
                .collect(),
        };
        let args: Vec<CString> = args
            .iter()
            .filter_map(|a| CString::new(a.as_str()).ok())
            .collect();
        let mut argv: Vec<*mut c_char> = args.iter().map(|a| a.as_ptr() as *mut c_char).collect();
        argv.push(ptr::null_mut());
        let mut opts = std::mem::MaybeUninit::<sys::ln_client_options>::uninit();
        // SAFETY: init fills every field.
        let mut opts = unsafe {
            sys::ln_client_options_init(opts.as_mut_ptr());
            opts.assume_init()
        };
        opts.manager = manager.as_ref().map_or(ptr::null(), |m| m.as_ptr());
        opts.argc = (argv.len() - 1) as i32;
        opts.argv = argv.as_mut_ptr();
        if let Some(t) = options.timeout {
            opts.timeout = t;
        }
        if options.no_reconnect {
            opts.flags |= sys::LN_CLIENT_NO_RECONNECT;
        }
        let mut raw = ptr::null_mut();
        // SAFETY: all pointers are valid for the call; libln does not keep argv.
        check(unsafe { sys::ln_client_create(&mut raw, c_name.as_ptr(), &opts) })?;
        // SAFETY: raw is a live client; the name is owned by it and copied here.
        let name = unsafe { CStr::from_ptr(sys::ln_client_name(raw)) }
            .to_string_lossy()
            .into_owned();
        Ok(Client {
            shared: Arc::new(Shared {
                raw: AtomicPtr::new(raw),
                closed: AtomicBool::new(false),
                gate: RwLock::new(()),
                setup: Mutex::new(()),
                name,
                keep: Mutex::new(Vec::new()),
            }),
        })
    }

    /// The name the manager gave this client (it may have appended "-2", ...).
    pub fn name(&self) -> &str {
        &self.shared.name
    }

    /// Closes the client: every handle of it returns `Error::ECLOSED` from now on.  libln's
    /// client is destroyed here, or, while a call of one of its handles is still running on
    /// another thread (or a loan or borrow is held), when the last handle is dropped.
    pub fn close(self) -> Result<()> {
        self.shared.close()
    }

    /// Sends a control command (a JSON object, docs/protocol.md "Control") to the manager
    /// and returns its JSON answer.
    pub fn control(&self, command: &str) -> Result<String> {
        let command = cstring("command", command)?;
        let open = self.shared.enter()?;
        let mut result: *mut c_char = ptr::null_mut();
        // SAFETY: the client is open (gate); result is freed with ln_free below.
        check(unsafe { sys::ln_control(open.raw(), command.as_ptr(), &mut result) })?;
        if result.is_null() {
            return Ok(String::new());
        }
        // SAFETY: result is a NUL-terminated string libln allocated.
        let text = unsafe { CStr::from_ptr(result) }
            .to_string_lossy()
            .into_owned();
        // SAFETY: handed out by ln_control, freed once.
        unsafe { sys::ln_free(result.cast()) };
        Ok(text)
    }

    /// The libln client, for a call right now on this thread; `ECLOSED` once closed.  Hold
    /// the returned guard for the duration of the call.
    #[allow(dead_code)]
    pub(crate) fn enter(&self) -> Result<Open<'_>> {
        self.shared.enter()
    }

    /// The state a handle keeps to outlive the `Client` value safely.
    pub(crate) fn shared(&self) -> &Arc<Shared> {
        &self.shared
    }

    /// The raw client pointer (null once closed).  Prefer [`Client::enter`], which keeps it
    /// alive for the call.
    #[allow(dead_code)]
    pub(crate) fn raw(&self) -> *mut sys::ln_client {
        self.shared.raw.load(Ordering::Acquire)
    }
}

impl Drop for Client {
    fn drop(&mut self) {
        let _ = self.shared.close();
    }
}

impl std::fmt::Debug for Client {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Client")
            .field("name", &self.shared.name)
            .finish()
    }
}
