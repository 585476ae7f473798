//! ln_zenoh_core: the native topic data path of ln_zenoh (docs/zenoh.md "The native core").
//!
//! The Python bridge keeps everything but the samples of topics: configuration, the manager's
//! lists, md serving and fetching, services, liveliness, ROS 2, statistics.  When this library
//! is found it opens the bridge's Zenoh session here, with the bridge's configuration plus a
//! Unix socket that the Python side's own session connects to as a client (a peer routes for
//! its clients, so the Python side's declarations reach the network through this session), and
//! the samples of topics go between libln's rings and Zenoh without Python: one thread per
//! outbound topic, inbound samples written in Zenoh's thread.
//!
//! C ABI (ctypes declarations in python/links_and_nodes/zenoh_bridge/native.py): every
//! function that can fail returns NULL or a negative number and writes why into err[errlen].
//! What both sides must agree on beyond the signatures is written once: the attachment in
//! python/links_and_nodes/wire/zenoh.schema (golden vectors in tests/golden), the counters'
//! order and the libln function table here (exported, checked by native.py when it loads the
//! core), the error codes in ln.h's table (build.rs).
//! Safety, for every function: handles are the ones this library returned and not yet closed,
//! strings are NUL-terminated, buffers are as large as their sizes say, and the callbacks
//! stay callable until the object they were given to is closed.
#![allow(clippy::missing_safety_doc)] // stated once above

mod attachment;
mod batch;
mod counters;
mod inbound;
mod libln;
mod log;
mod outbound;
mod rate;

use std::ffi::{c_char, c_int, c_void, CStr};
use std::panic::{catch_unwind, AssertUnwindSafe};

use zenoh::{Session, Wait};

use counters::{Counters, Shared};
use inbound::{InRule, InTopic, SampleFn};
use libln::{LnFns, Port};
use log::{Complainer, LogFn, Logger};
use outbound::{MatchFn, OutSpec, OutTopic};
use rate::RateLimit;

pub struct Core {
    session: Session,
    fns: LnFns,
    logger: Logger,
}

fn write_err(err: *mut c_char, errlen: usize, text: &str) {
    if err.is_null() || errlen == 0 {
        return;
    }
    let bytes = text.as_bytes();
    let n = bytes.len().min(errlen - 1);
    // SAFETY: the caller gives a buffer of errlen bytes.
    unsafe {
        std::ptr::copy_nonoverlapping(bytes.as_ptr(), err as *mut u8, n);
        *err.add(n) = 0;
    }
}

fn text_arg<'a>(p: *const c_char, what: &str) -> Result<&'a str, String> {
    if p.is_null() {
        return Err(format!("{what} is NULL"));
    }
    // SAFETY: the caller gives a NUL-terminated string.
    unsafe { CStr::from_ptr(p) }.to_str().map_err(|_| format!("{what} is not UTF-8"))
}

/// Runs `f`, turning an error or a panic into NULL and a text in err.
fn guarded<T>(err: *mut c_char, errlen: usize, f: impl FnOnce() -> Result<T, String>) -> Option<T> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(v)) => Some(v),
        Ok(Err(text)) => {
            write_err(err, errlen, &text);
            None
        }
        Err(_) => {
            write_err(err, errlen, "ln_zenoh_core: internal error (panic)");
            None
        }
    }
}

fn boxed<T>(v: Option<T>) -> *mut T {
    v.map_or(std::ptr::null_mut(), |v| Box::into_raw(Box::new(v)))
}

/// The counters' field names in their order (counters.rs), space-separated: the Python side
/// checks them against its struct before it uses the core.  A static string.
#[no_mangle]
pub extern "C" fn lnz_counter_names() -> *const c_char {
    counters::NAMES.as_ptr() as *const c_char
}

/// The libln functions lnz_open's table holds, in order, as `ln_` + these space-separated
/// names (libln.rs): the Python side builds the table from them.  A static string.
#[no_mangle]
pub extern "C" fn lnz_libln_functions() -> *const c_char {
    libln::FN_NAMES.as_ptr() as *const c_char
}

/// Opens the Zenoh session from a configuration in JSON5 (what the Python side built from
/// the bridge's settings).
#[no_mangle]
pub unsafe extern "C" fn lnz_open(config_json5: *const c_char, fns: *const LnFns, log: LogFn,
                           log_ctx: *mut c_void, err: *mut c_char, errlen: usize) -> *mut Core {
    boxed(guarded(err, errlen, || {
        let text = text_arg(config_json5, "the configuration")?;
        if fns.is_null() {
            return Err("the libln function table is NULL".into());
        }
        let config = zenoh::Config::from_json5(text)
            .map_err(|e| format!("the Zenoh configuration is refused: {e}"))?;
        let session = zenoh::open(config).wait()
            .map_err(|e| format!("cannot open the Zenoh session: {e}"))?;
        // SAFETY: checked non-NULL; the table is copied.
        Ok(Core { session, fns: unsafe { *fns }, logger: Logger::new(log, log_ctx) })
    }))
}

/// The session's Zenoh id as text into out[size]; its length, or -1.
#[no_mangle]
pub unsafe extern "C" fn lnz_zid(core: *const Core, out: *mut c_char, size: usize) -> c_int {
    if core.is_null() {
        return -1;
    }
    // SAFETY: a handle from lnz_open not yet closed.
    let zid = unsafe { &*core }.session.zid().to_string();
    write_err(out, size, &zid);
    zid.len() as c_int
}

/// Closes the session; every topic and rule of it must be closed before.
#[no_mangle]
pub unsafe extern "C" fn lnz_close(core: *mut Core) {
    if core.is_null() {
        return;
    }
    // SAFETY: a handle from lnz_open, given up here.
    let core = unsafe { Box::from_raw(core) };
    let _ = catch_unwind(AssertUnwindSafe(|| core.session.close().wait()));
}

/// An outbound topic: reads `port` (an ln_inport of `size`-byte samples) and puts each sample
/// on `key` while a remote subscriber matches, and in batches on `batch_key` (NULL: none)
/// while a bridge takes them (batch.rs).  `label` prefixes what it says ("topic 'x'").
#[no_mangle]
pub unsafe extern "C" fn lnz_out_open(core: *const Core, key: *const c_char,
                               batch_key: *const c_char, port: *mut c_void,
                               size: usize, md_name: *const c_char, layout_hash: u64,
                               queued: c_int, rate_hz: f64, counters: *const Counters,
                               label: *const c_char, on_match: MatchFn, match_ctx: *mut c_void,
                               err: *mut c_char, errlen: usize) -> *mut OutTopic {
    boxed(guarded(err, errlen, || {
        if core.is_null() || port.is_null() || counters.is_null() {
            return Err("a NULL handle".into());
        }
        // SAFETY: a handle from lnz_open not yet closed.
        let core = unsafe { &*core };
        let batch_key = if batch_key.is_null() {
            None
        } else {
            Some(text_arg(batch_key, "the batch key")?.to_string())
        };
        let spec = OutSpec { key: text_arg(key, "the key")?.to_string(), batch_key,
                             port: Port(port), size,
                             md_name: text_arg(md_name, "the md name")?.to_string(), layout_hash,
                             queued: queued != 0, rate_hz, counters: Shared(counters), on_match,
                             match_ctx: match_ctx as usize };
        let complainer = Complainer::new(core.logger, text_arg(label, "the label")?.to_string());
        OutTopic::open(&core.session, core.fns, spec, complainer)
    }))
}

/// 1 while a remote subscriber matches the topic's key, else 0.
#[no_mangle]
pub unsafe extern "C" fn lnz_out_matching(out: *const OutTopic) -> c_int {
    // SAFETY: a handle from lnz_out_open not yet closed.
    (!out.is_null() && unsafe { &*out }.matching()) as c_int
}

/// Stops the topic; its port and counters are not used any more when this returns.
#[no_mangle]
pub unsafe extern "C" fn lnz_out_close(out: *mut OutTopic) {
    if !out.is_null() {
        // SAFETY: a handle from lnz_out_open, given up here.
        let mut out = unsafe { Box::from_raw(out) };
        let _ = catch_unwind(AssertUnwindSafe(|| out.close()));
    }
}

/// An inbound rule: subscribes to `key_expr` (`<remote>/topic/...`); samples of keys not
/// handed over go to on_sample(ctx, ...).  `remote` (NULL: none) is the prefix of the bridge
/// whose batches lnz_in_batch may take.
#[no_mangle]
pub unsafe extern "C" fn lnz_in_open(core: *const Core, key_expr: *const c_char,
                              remote: *const c_char, on_sample: SampleFn,
                              ctx: *mut c_void, err: *mut c_char, errlen: usize) -> *mut InRule {
    boxed(guarded(err, errlen, || {
        if core.is_null() {
            return Err("a NULL handle".into());
        }
        // SAFETY: a handle from lnz_open not yet closed.
        let core = unsafe { &*core };
        let remote = if remote.is_null() { None } else { Some(text_arg(remote, "the remote")?) };
        InRule::open(&core.session, text_arg(key_expr, "the key expression")?, remote, core.fns,
                     core.logger, on_sample, ctx as usize)
    }))
}

/// Takes the remote bridge's batches instead of its per-topic samples (on 1) or back (0);
/// 0, or -1 with err.
#[no_mangle]
pub unsafe extern "C" fn lnz_in_batch(rule: *const InRule, on: c_int, err: *mut c_char,
                                      errlen: usize) -> c_int {
    guarded(err, errlen, || {
        if rule.is_null() {
            return Err("a NULL handle".into());
        }
        // SAFETY: a handle from lnz_in_open not yet closed.
        unsafe { &*rule }.set_batch(on != 0).map(|()| 0)
    }).unwrap_or(-1)
}

/// Malformed batches the rule dropped for topics not handed over (those of handed-over topics
/// are in their counters).
#[no_mangle]
pub unsafe extern "C" fn lnz_in_bad_batches(rule: *const InRule) -> u64 {
    // SAFETY: a handle from lnz_in_open not yet closed.
    if rule.is_null() { 0 } else { unsafe { &*rule }.bad_batches() }
}

/// Hands the topic of `key` over: its samples are checked against md_name, layout_hash and
/// size and written to `port` (an ln_outport) here; for a queued topic first through
/// `wait_port` (one with LN_PUBLISH_WAIT_FOR_SUBSCRIBERS, see inbound::HOLD_S), NULL for a
/// latest one; `congested` as the Python side left the topic.  0, or -1 with err.
#[no_mangle]
pub unsafe extern "C" fn lnz_in_ready(rule: *const InRule, key: *const c_char,
                               port: *mut c_void, wait_port: *mut c_void, size: usize,
                               md_name: *const c_char, layout_hash: u64, rate_hz: f64,
                               congested: c_int, counters: *const Counters,
                               label: *const c_char,
                               err: *mut c_char, errlen: usize) -> c_int {
    guarded(err, errlen, || {
        if rule.is_null() || port.is_null() || counters.is_null() {
            return Err("a NULL handle".into());
        }
        // SAFETY: a handle from lnz_in_open not yet closed.
        let rule = unsafe { &*rule };
        let topic = InTopic { port: Port(port), writing: std::sync::Mutex::new(()),
                              wait_port: (!wait_port.is_null()).then_some(Port(wait_port)),
                              congested: std::sync::atomic::AtomicBool::new(congested != 0),
                              size,
                              md_name: text_arg(md_name, "the md name")?.to_string(),
                              layout_hash, rate: RateLimit::new(rate_hz),
                              counters: Shared(counters),
                              complainer: Complainer::new(rule.logger(),
                                                          text_arg(label, "the label")?.to_string()) };
        rule.ready(text_arg(key, "the key")?.to_string(), topic);
        Ok(0)
    }).unwrap_or(-1)
}

/// Handles a sample of the handed-over `key` that reached the Python side while it was
/// handed over (att_len -1: no attachment); 0, or -1 if `key` is not handed over.
#[no_mangle]
pub unsafe extern "C" fn lnz_in_offer(rule: *const InRule, key: *const c_char, payload: *const u8,
                                      len: usize, att: *const u8, att_len: isize) -> c_int {
    if rule.is_null() || (payload.is_null() && len > 0) {
        return -1;
    }
    let Ok(key) = text_arg(key, "the key") else { return -1 };
    let payload: &[u8] = if len == 0 { &[] } else { std::slice::from_raw_parts(payload, len) };
    let att = (att_len >= 0 && !att.is_null())
        .then(|| std::slice::from_raw_parts(att, att_len as usize));
    // SAFETY: a handle from lnz_in_open not yet closed; buffers as the caller says.
    match catch_unwind(AssertUnwindSafe(|| (*rule).offer(key, payload, att))) {
        Ok(true) => 0,
        _ => -1,
    }
}

/// Takes the topic of `key` back; its port and counters are not used when this returns.
#[no_mangle]
pub unsafe extern "C" fn lnz_in_forget(rule: *const InRule, key: *const c_char) {
    if rule.is_null() {
        return;
    }
    if let Ok(key) = text_arg(key, "the key") {
        // SAFETY: a handle from lnz_in_open not yet closed.
        let _ = catch_unwind(AssertUnwindSafe(|| unsafe { &*rule }.forget(key)));
    }
}

/// Ends the rule's subscription and forgets its topics.
#[no_mangle]
pub unsafe extern "C" fn lnz_in_close(rule: *mut InRule) {
    if !rule.is_null() {
        // SAFETY: a handle from lnz_in_open, given up here.
        let mut rule = unsafe { Box::from_raw(rule) };
        let _ = catch_unwind(AssertUnwindSafe(|| rule.close()));
    }
}
