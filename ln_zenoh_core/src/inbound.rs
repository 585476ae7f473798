//! An inbound rule (Zenoh -> links_and_nodes): one Zenoh subscription for the rule's key
//! expression.  A topic the Python side has set up (its md found and checked, its publisher
//! created: inbound.py) is handed over with `ready`, and from then its samples are checked and
//! written into the topic right in Zenoh's thread; samples of other keys go to the Python
//! side's callback, which decides, sets the topic up and hands it over.  The checks, counters
//! and complaints are those of inbound.py.

use std::collections::HashMap;
use std::ffi::c_void;
use std::sync::atomic::{AtomicBool, Ordering::Relaxed, Ordering::SeqCst};
use std::sync::{Arc, Mutex, RwLock};

use zenoh::bytes::ZBytes;
use zenoh::pubsub::Subscriber;
use zenoh::sample::Sample;
use zenoh::{Session, Wait};

use crate::attachment;
use crate::counters::{add, get, set, Shared};
use crate::libln::{LnFns, Port, LN_EAGAIN, LN_ETIMEOUT};
use crate::log::{Complainer, Logger};
use crate::rate::RateLimit;

/// The Python side's handler of a sample of a key not handed over (yet): key, payload and
/// attachment (att_len -1: none).
pub type SampleFn = unsafe extern "C" fn(ctx: *mut c_void, key: *const u8, key_len: usize,
                                         payload: *const u8, len: usize, att: *const u8,
                                         att_len: isize);

/// Seconds a write of a queued topic waits for a local subscriber with no free buffer (through
/// `wait_port`, which publishes with LN_PUBLISH_WAIT_FOR_SUBSCRIBERS): meanwhile Zenoh holds
/// the sender back.  When that times out the sample is written through `port`, which does not
/// wait (that subscriber loses its oldest sample, the others get it: counted as `forced`), and
/// the topic is `congested`: writes do not wait until one finds room again, so a subscriber
/// that stopped reading costs the link one pause, not one per sample.
pub const HOLD_S: f64 = 0.05;

pub struct InTopic {
    pub port: Port,
    pub wait_port: Option<Port>, // queued topics
    pub writing: Mutex<()>, // one writer of the ports at a time, as libln wants
    pub congested: AtomicBool,
    pub size: usize,
    pub md_name: String,
    pub layout_hash: u64,
    pub rate: RateLimit,
    pub counters: Shared,
    pub complainer: Complainer,
}

struct RuleState {
    topics: RwLock<HashMap<String, InTopic>>,
    closed: AtomicBool,
    on_sample: SampleFn,
    ctx: usize,
    fns: LnFns,
    logger: Logger,
}

pub struct InRule {
    state: Arc<RuleState>,
    subscriber: Option<Subscriber<()>>,
}

impl InRule {
    pub fn open(session: &Session, key_expr: &str, fns: LnFns, logger: Logger,
                on_sample: SampleFn, ctx: usize) -> Result<InRule, String> {
        let state = Arc::new(RuleState { topics: RwLock::new(HashMap::new()),
                                         closed: AtomicBool::new(false), on_sample, ctx, fns,
                                         logger });
        let st = state.clone();
        let subscriber = session.declare_subscriber(key_expr.to_string())
            .callback(move |sample| on_sample_of(&st, &sample))
            .wait()
            .map_err(|e| format!("cannot subscribe to {key_expr}: {e}"))?;
        Ok(InRule { state, subscriber: Some(subscriber) })
    }

    /// What the rule's topics say goes here.
    pub fn logger(&self) -> Logger {
        self.state.logger
    }

    /// From now on samples of `key` are handled here.
    pub fn ready(&self, key: String, topic: InTopic) {
        self.state.topics.write().unwrap_or_else(|e| e.into_inner()).insert(key, topic);
    }

    /// Handles a sample of a handed-over `key` that reached the Python side while the key was
    /// handed over; false if `key` is not handed over.
    pub fn offer(&self, key: &str, payload: &[u8], att: Option<&[u8]>) -> bool {
        let topics = self.state.topics.read().unwrap_or_else(|e| e.into_inner());
        match topics.get(key) {
            Some(topic) => {
                handle(&self.state.fns, topic, payload, att);
                true
            }
            None => false,
        }
    }

    /// Samples of `key` go to the Python side again; its port and counters are not used any
    /// more when this returns (a write in progress holds the read lock this waits for).
    pub fn forget(&self, key: &str) {
        self.state.topics.write().unwrap_or_else(|e| e.into_inner()).remove(key);
    }

    pub fn close(&mut self) {
        self.state.closed.store(true, SeqCst);
        if let Some(sub) = self.subscriber.take() {
            let _ = sub.undeclare().wait();
        }
        self.state.topics.write().unwrap_or_else(|e| e.into_inner()).clear();
    }
}

impl Drop for InRule {
    fn drop(&mut self) {
        self.close();
    }
}

fn on_sample_of(state: &RuleState, sample: &Sample) {
    if state.closed.load(SeqCst) {
        return;
    }
    let key = sample.key_expr().as_str();
    let att = sample.attachment().map(|a| a.to_bytes());
    {
        let topics = state.topics.read().unwrap_or_else(|e| e.into_inner());
        if let Some(topic) = topics.get(key) {
            handle(&state.fns, topic, sample.payload(), att.as_deref());
            return;
        }
    }
    if state.closed.load(SeqCst) {
        return;
    }
    let payload = sample.payload().to_bytes();
    let (att_ptr, att_len) = match &att {
        Some(a) => (a.as_ptr(), a.len() as isize),
        None => (std::ptr::null(), -1),
    };
    // SAFETY: a ctypes callback kept alive by the Python side until close(); the buffers live
    // for the duration of the call.
    unsafe {
        (state.on_sample)(state.ctx as *mut c_void, key.as_ptr(), key.len(), payload.as_ptr(),
                          payload.len(), att_ptr, att_len)
    };
}

/// A sample's payload: as Zenoh holds it (in pieces) or as the Python side hands it over.
pub trait Payload {
    fn len(&self) -> usize;
    /// Copies the payload to `dst`, which has room for len() bytes.
    ///
    /// # Safety
    /// `dst` must be valid for len() bytes of writes.
    unsafe fn copy_to(&self, dst: *mut u8);
}

impl Payload for ZBytes {
    fn len(&self) -> usize {
        ZBytes::len(self)
    }

    unsafe fn copy_to(&self, dst: *mut u8) {
        let mut at = 0usize;
        for piece in self.slices() {
            std::ptr::copy_nonoverlapping(piece.as_ptr(), dst.add(at), piece.len());
            at += piece.len();
        }
    }
}

impl Payload for [u8] {
    fn len(&self) -> usize {
        <[u8]>::len(self)
    }

    unsafe fn copy_to(&self, dst: *mut u8) {
        std::ptr::copy_nonoverlapping(self.as_ptr(), dst, self.len());
    }
}

fn handle<P: Payload + ?Sized>(fns: &LnFns, topic: &InTopic, payload: &P, att: Option<&[u8]>) {
    let c = topic.counters.get();
    add(&c.received, 1);
    let att = match attachment::decode(att) {
        Ok(a) => a,
        Err(why) => {
            add(&c.bad_attachment, 1);
            topic.complainer.complain("attachment", || {
                format!("sample dropped: {why} (counted as bad_attachment)")
            });
            return;
        }
    };
    if att.md_name != topic.md_name || att.layout_hash != topic.layout_hash {
        add(&c.refused, 1);
        topic.complainer.complain("md", || {
            format!("sample of md '{}' 0x{:016x} dropped: this topic carries '{}' 0x{:016x}",
                    att.md_name, att.layout_hash, topic.md_name, topic.layout_hash)
        });
        return;
    }
    if payload.len() != topic.size {
        add(&c.bad_size, 1);
        topic.complainer.complain("size", || {
            format!("sample of {} bytes dropped: md '{}' has {} (counted as bad_size)",
                    payload.len(), att.md_name, topic.size)
        });
        return;
    }
    let last = get(&c.last_seq);
    if last != 0 && att.seq > last + 1 {
        add(&c.gaps, att.seq - last - 1);
    }
    set(&c.last_seq, att.seq);
    if !topic.rate.admit() {
        add(&c.rate_limited, 1);
        return;
    }
    let rc = {
        let _one = topic.writing.lock().unwrap_or_else(|e| e.into_inner());
        match topic.wait_port {
            None => write(fns, topic.port, payload, 0.0),
            Some(wait_port) => {
                let congested = topic.congested.load(Relaxed);
                let rc = write(fns, wait_port, payload, if congested { 0.0 } else { HOLD_S });
                if rc == LN_ETIMEOUT || rc == LN_EAGAIN {
                    if !congested {
                        topic.congested.store(true, Relaxed);
                        topic.complainer.complain("forced", || {
                            format!("a subscriber here took no sample for {HOLD_S} s: it loses \
                                     its oldest ones (counted as forced) until it reads again")
                        });
                    }
                    add(&c.forced, 1);
                    write(fns, topic.port, payload, 0.0)
                } else {
                    if rc >= 0 {
                        topic.congested.store(false, Relaxed);
                    }
                    rc
                }
            }
        }
    };
    if rc < 0 {
        add(&c.errors, 1);
        topic.complainer.complain("error", || format!("publishing failed: {}", fns.error_text(rc)));
        return;
    }
    add(&c.published, 1);
    add(&c.bytes, topic.size as u64);
}

/// Copies the payload, in the pieces Zenoh holds it in, into a loaned slot of the topic and
/// publishes it (no copy into one buffer first); LN_OK or the LN_E* code.
fn write<P: Payload + ?Sized>(fns: &LnFns, port: Port, payload: &P, timeout: f64) -> std::ffi::c_int {
    let mut slot: *mut c_void = std::ptr::null_mut();
    // SAFETY: the port is open while the topic is in the map (forget() waits for this), and
    // written by one thread at a time (the caller holds the topic's `writing`).
    let rc = unsafe { (fns.write_loan)(port.0, &mut slot, timeout) };
    if rc < 0 {
        return rc;
    }
    // SAFETY: the slot has the topic's size, which the payload's length was checked against.
    unsafe { payload.copy_to(slot as *mut u8) };
    // SAFETY: the loan of this thread, above.
    unsafe { (fns.write_commit)(port.0) }
}
