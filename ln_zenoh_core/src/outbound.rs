//! An outbound topic (links_and_nodes -> Zenoh): a thread reads every sample the Python
//! side's subscription gives (zero-copy borrow, one copy into the Zenoh payload) and puts it
//! on the topic's key with its attachment, but only while a remote subscriber matches
//! (Zenoh's matching listener); the semantics and counters are those of outbound.py.

use std::ffi::{c_int, c_void};
use std::sync::atomic::{AtomicBool, Ordering::Relaxed, Ordering::SeqCst};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use zenoh::matching::MatchingListener;
use zenoh::pubsub::Publisher;
use zenoh::qos::CongestionControl;
use zenoh::{Session, Wait};

use crate::attachment::Encoder;
use crate::counters::{add, set, Shared};
use crate::libln::{LnFns, Port, SampleInfo, LN_EAGAIN, LN_EOVERRUN, LN_ETIMEOUT};
use crate::log::Complainer;
use crate::rate::RateLimit;

const READ_SLICE: f64 = 0.2; // seconds a read waits before the stop flag is looked at

pub type MatchFn = unsafe extern "C" fn(ctx: *mut c_void, matching: c_int);

pub struct OutSpec {
    pub key: String,
    pub port: Port,
    pub size: usize,
    pub md_name: String,
    pub layout_hash: u64,
    pub queued: bool,
    pub rate_hz: f64,
    pub counters: Shared,
    pub on_match: MatchFn,
    pub match_ctx: usize,
}

struct OutState {
    stop: AtomicBool,
    matching: AtomicBool,
    closed: AtomicBool,
}

pub struct OutTopic {
    state: Arc<OutState>,
    thread: Option<JoinHandle<()>>,
    listener: Option<MatchingListener<()>>,
}

impl OutTopic {
    pub fn open(session: &Session, fns: LnFns, spec: OutSpec, complainer: Complainer)
                -> Result<OutTopic, String> {
        let encoder = Encoder::new(&spec.md_name, spec.layout_hash)?;
        let congestion = if spec.queued { CongestionControl::Block } else { CongestionControl::Drop };
        let publisher = session.declare_publisher(spec.key.clone())
            .congestion_control(congestion)
            .express(!spec.queued)
            .wait()
            .map_err(|e| format!("cannot declare the publisher of {}: {e}", spec.key))?;
        let state = Arc::new(OutState { stop: AtomicBool::new(false),
                                       matching: AtomicBool::new(false),
                                       closed: AtomicBool::new(false) });
        let (on_match, ctx) = (spec.on_match, spec.match_ctx);
        let st = state.clone();
        let listener = publisher.matching_listener()
            .callback(move |status| {
                st.matching.store(status.matching(), SeqCst);
                if !st.closed.load(SeqCst) {
                    // SAFETY: a ctypes callback the Python side keeps alive until close.
                    unsafe { on_match(ctx as *mut c_void, status.matching() as c_int) };
                }
            })
            .wait()
            .map_err(|e| format!("cannot declare the matching listener of {}: {e}", spec.key))?;
        // A change before the listener existed is not reported by it: look once now.
        if let Ok(status) = publisher.matching_status().wait() {
            state.matching.fetch_or(status.matching(), SeqCst);
        }
        let st = state.clone();
        let thread = std::thread::Builder::new()
            .name(format!("lnz out {}", spec.key))
            .spawn(move || run(publisher, fns, spec, encoder, st, complainer))
            .map_err(|e| format!("cannot start a thread: {e}"))?;
        Ok(OutTopic { state, thread: Some(thread), listener: Some(listener) })
    }

    pub fn matching(&self) -> bool {
        self.state.matching.load(SeqCst)
    }

    /// Stops the reader (within READ_SLICE) and the listener; the port and the counters are
    /// not used any more when this returns.
    pub fn close(&mut self) {
        self.state.closed.store(true, SeqCst);
        self.state.stop.store(true, SeqCst);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
        if let Some(listener) = self.listener.take() {
            let _ = listener.undeclare().wait();
        }
    }
}

impl Drop for OutTopic {
    fn drop(&mut self) {
        self.close();
    }
}

fn run(publisher: Publisher<'static>, fns: LnFns, spec: OutSpec, encoder: Encoder,
       state: Arc<OutState>, complainer: Complainer) {
    let counters = spec.counters.get();
    let rate = RateLimit::new(spec.rate_hz);
    let port = spec.port;
    while !state.stop.load(Relaxed) {
        let mut data: *const c_void = std::ptr::null();
        let mut info = SampleInfo::default();
        // SAFETY: the port stays open until close() joined this thread; one reader.
        let rc = unsafe { (fns.read_borrow)(port.0, &mut data, READ_SLICE, &mut info) };
        if rc == LN_ETIMEOUT || rc == LN_EAGAIN {
            continue;
        }
        if rc < 0 {
            add(&counters.errors, 1);
            complainer.complain("read", || format!("read failed: {}", fns.error_text(rc)));
            sleep_unless_stopped(&state.stop, Duration::from_secs(1));
            continue;
        }
        // SAFETY: a borrowed sample is `size` bytes in the ring until the release below.
        let payload = unsafe { std::slice::from_raw_parts(data as *const u8, spec.size) }.to_vec();
        let released = unsafe { (fns.read_release)(port.0) };
        add(&counters.read, 1);
        add(&counters.overruns, info.overruns);
        set(&counters.last_seq, info.seq);
        if released == LN_EOVERRUN {
            add(&counters.overruns, 1); // overwritten while copied: not sent
            continue;
        }
        if !state.matching.load(Relaxed) {
            add(&counters.unmatched, 1);
            continue;
        }
        if !rate.admit() {
            add(&counters.rate_limited, 1);
            continue;
        }
        match publisher.put(payload).attachment(encoder.encode(info.seq, info.timestamp_ns)).wait() {
            Ok(()) => {
                add(&counters.sent, 1);
                add(&counters.bytes, spec.size as u64);
            }
            Err(e) => {
                add(&counters.errors, 1);
                complainer.complain("put", || format!("put failed: {e}"));
            }
        }
    }
    let _ = publisher.undeclare().wait();
}

fn sleep_unless_stopped(stop: &AtomicBool, total: Duration) {
    let step = Duration::from_millis(50);
    let mut left = total;
    while !left.is_zero() && !stop.load(Relaxed) {
        let d = left.min(step);
        std::thread::sleep(d);
        left -= d;
    }
}
