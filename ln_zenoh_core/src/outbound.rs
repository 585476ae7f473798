//! An outbound topic (links_and_nodes -> Zenoh): a thread reads every sample the Python
//! side's subscription gives (zero-copy borrow, one copy into the Zenoh payload) and puts it
//! on the topic's key with its attachment, but only while a remote subscriber matches
//! (Zenoh's matching listener); the semantics and counters are those of outbound.py.
//! With a batch key (batch.rs) the samples also go, in batches, to the bridges subscribed to
//! that key: several per Zenoh message when several are waiting in the ring, a lone one at
//! once, never held back for more.

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
use crate::batch::Builder;
use crate::counters::{add, set, Counters, Shared};
use crate::libln::{LnFns, Port, SampleInfo, LN_EAGAIN, LN_EOVERRUN, LN_ETIMEOUT};
use crate::log::Complainer;
use crate::rate::RateLimit;

const READ_SLICE: f64 = 0.2; // seconds a read waits before the stop flag is looked at

pub type MatchFn = unsafe extern "C" fn(ctx: *mut c_void, matching: c_int);

pub struct OutSpec {
    pub key: String,
    pub batch_key: Option<String>, // None: no batches (--batch off)
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
    matching: AtomicBool,       // a subscriber of the topic's key
    batch_matching: AtomicBool, // a bridge subscribed to the batch key
    reported: AtomicBool,       // what on_match was told last: either of the two
    closed: AtomicBool,
}

impl OutState {
    /// Tells the Python side when "a remote subscriber matches" (either key) changes.
    fn report(&self, on_match: MatchFn, ctx: usize) {
        let now = self.matching.load(SeqCst) || self.batch_matching.load(SeqCst);
        if self.reported.swap(now, SeqCst) != now && !self.closed.load(SeqCst) {
            // SAFETY: a ctypes callback the Python side keeps alive until close.
            unsafe { on_match(ctx as *mut c_void, now as c_int) };
        }
    }
}

pub struct OutTopic {
    state: Arc<OutState>,
    thread: Option<JoinHandle<()>>,
    listeners: Vec<MatchingListener<()>>,
}

fn declare(session: &Session, key: &str, queued: bool) -> Result<Publisher<'static>, String> {
    let congestion = if queued { CongestionControl::Block } else { CongestionControl::Drop };
    session.declare_publisher(key.to_string())
        .congestion_control(congestion)
        .express(!queued)
        .wait()
        .map_err(|e| format!("cannot declare the publisher of {key}: {e}"))
}

/// Keeps `flag` to the matching status of `publisher` and reports changes.
fn listen(publisher: &Publisher<'static>, state: &Arc<OutState>, flag: fn(&OutState) -> &AtomicBool,
          on_match: MatchFn, ctx: usize) -> Result<MatchingListener<()>, String> {
    let st = state.clone();
    let listener = publisher.matching_listener()
        .callback(move |status| {
            flag(&st).store(status.matching(), SeqCst);
            st.report(on_match, ctx);
        })
        .wait()
        .map_err(|e| format!("cannot declare the matching listener of {}: {e}",
                             publisher.key_expr()))?;
    // A change before the listener existed is not reported by it: look once now.
    if let Ok(status) = publisher.matching_status().wait() {
        flag(state).fetch_or(status.matching(), SeqCst);
    }
    Ok(listener)
}

impl OutTopic {
    pub fn open(session: &Session, fns: LnFns, spec: OutSpec, complainer: Complainer)
                -> Result<OutTopic, String> {
        let encoder = Encoder::new(&spec.md_name, spec.layout_hash)?;
        let publisher = declare(session, &spec.key, spec.queued)?;
        let batcher = match &spec.batch_key {
            Some(key) => Some(declare(session, key, spec.queued)?),
            None => None,
        };
        let state = Arc::new(OutState { stop: AtomicBool::new(false),
                                       matching: AtomicBool::new(false),
                                       batch_matching: AtomicBool::new(false),
                                       reported: AtomicBool::new(false),
                                       closed: AtomicBool::new(false) });
        let (on_match, ctx) = (spec.on_match, spec.match_ctx);
        let mut listeners = vec![listen(&publisher, &state, |s| &s.matching, on_match, ctx)?];
        if let Some(b) = &batcher {
            listeners.push(listen(b, &state, |s| &s.batch_matching, on_match, ctx)?);
        }
        state.reported.store(state.matching.load(SeqCst) || state.batch_matching.load(SeqCst),
                             SeqCst);
        let st = state.clone();
        let thread = std::thread::Builder::new()
            .name(format!("lnz out {}", spec.key))
            .spawn(move || {
                let out = Out { publisher, batcher, encoder, complainer, batch: Builder::new() };
                run(out, fns, spec, st)
            })
            .map_err(|e| format!("cannot start a thread: {e}"))?;
        Ok(OutTopic { state, thread: Some(thread), listeners })
    }

    /// A remote subscriber of the topic's key, or a bridge taking its batches.
    pub fn matching(&self) -> bool {
        self.state.matching.load(SeqCst) || self.state.batch_matching.load(SeqCst)
    }

    /// Stops the reader (within READ_SLICE) and the listeners; the port and the counters are
    /// not used any more when this returns.
    pub fn close(&mut self) {
        self.state.closed.store(true, SeqCst);
        self.state.stop.store(true, SeqCst);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
        for listener in self.listeners.drain(..) {
            let _ = listener.undeclare().wait();
        }
    }
}

impl Drop for OutTopic {
    fn drop(&mut self) {
        self.close();
    }
}

/// What the reader thread puts with.
struct Out {
    publisher: Publisher<'static>,
    batcher: Option<Publisher<'static>>,
    encoder: Encoder,
    complainer: Complainer,
    batch: Builder,
}

impl Out {
    /// Puts the batch being filled, if any.
    fn flush(&mut self, counters: &Counters) {
        let Some((bytes, _count, (seq, time))) = self.batch.take() else { return };
        let Some(batcher) = &self.batcher else { return };
        match batcher.put(bytes).attachment(self.encoder.encode(seq, time)).wait() {
            Ok(()) => add(&counters.batches, 1),
            Err(e) => {
                add(&counters.errors, 1);
                self.complainer.complain("put", || format!("put of a batch failed: {e}"));
            }
        }
    }
}

fn run(mut out: Out, fns: LnFns, spec: OutSpec, state: Arc<OutState>) {
    let counters = spec.counters.get();
    let rate = RateLimit::new(spec.rate_hz);
    let port = spec.port;
    while !state.stop.load(Relaxed) {
        let mut data: *const c_void = std::ptr::null();
        let mut info = SampleInfo::default();
        // A batch being filled goes as soon as the ring has nothing more: never waits.
        let timeout = if out.batch.is_empty() { READ_SLICE } else { 0.0 };
        // SAFETY: the port stays open until close() joined this thread; one reader.
        let rc = unsafe { (fns.read_borrow)(port.0, &mut data, timeout, &mut info) };
        if rc == LN_ETIMEOUT || rc == LN_EAGAIN {
            out.flush(counters);
            continue;
        }
        if rc < 0 {
            out.flush(counters);
            add(&counters.errors, 1);
            out.complainer.complain("read", || format!("read failed: {}", fns.error_text(rc)));
            sleep_unless_stopped(&state.stop, Duration::from_secs(1));
            continue;
        }
        let to_topic = state.matching.load(Relaxed);
        let to_batch = out.batcher.is_some() && state.batch_matching.load(Relaxed);
        // SAFETY: a borrowed sample is `size` bytes in the ring until the release below.
        let sample = unsafe { std::slice::from_raw_parts(data as *const u8, spec.size) };
        let payload = to_topic.then(|| sample.to_vec());
        let mark = to_batch.then(|| out.batch.push(info.seq, info.timestamp_ns, sample));
        let released = unsafe { (fns.read_release)(port.0) };
        add(&counters.read, 1);
        add(&counters.overruns, info.overruns);
        set(&counters.last_seq, info.seq);
        let admitted = released != LN_EOVERRUN && (to_topic || to_batch) && rate.admit();
        if !admitted {
            if let Some(mark) = mark {
                out.batch.undo(mark);
            }
            if released == LN_EOVERRUN {
                add(&counters.overruns, 1); // overwritten while copied: not sent
            } else if !(to_topic || to_batch) {
                add(&counters.unmatched, 1);
            } else {
                add(&counters.rate_limited, 1);
            }
            continue;
        }
        let mut sent = to_batch;
        if let Some(payload) = payload {
            match out.publisher.put(payload).attachment(out.encoder.encode(info.seq, info.timestamp_ns))
                .wait() {
                Ok(()) => sent = true,
                Err(e) => {
                    add(&counters.errors, 1);
                    out.complainer.complain("put", || format!("put failed: {e}"));
                }
            }
        }
        if sent {
            add(&counters.sent, 1);
            add(&counters.bytes, spec.size as u64);
        }
        if out.batch.full() {
            out.flush(counters);
        }
    }
    out.flush(counters);
    if let Some(batcher) = out.batcher {
        let _ = batcher.undeclare().wait();
    }
    let _ = out.publisher.undeclare().wait();
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
