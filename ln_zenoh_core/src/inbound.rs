//! An inbound rule (Zenoh -> links_and_nodes): one Zenoh subscription for the rule's key
//! expression.  A topic the Python side has set up (its md found and checked, its publisher
//! created: inbound.py) is handed over with `ready`, and from then its samples are checked and
//! written into the topic right in Zenoh's thread; samples of other keys go to the Python
//! side's callback, which decides, sets the topic up and hands it over.  The checks, counters
//! and complaints are those of inbound.py.
//!
//! While the remote bridge offers batches (`set_batch`, batch.rs) the rule subscribes to the
//! remote's batch keys instead of its per-topic keys, and each sample of a batch is handled as
//! one of the per-topic key.  While both subscriptions exist (the switch) the sender puts each
//! sample on both: per topic, a sample that comes the other way than the last one and does
//! not come after it (seq) within SWITCH_WINDOW is a repeat and dropped.

use std::collections::HashMap;
use std::ffi::c_void;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering::Relaxed, Ordering::SeqCst};
use std::sync::{Arc, Mutex, RwLock};
use std::time::{Duration, Instant};

use zenoh::bytes::ZBytes;
use zenoh::pubsub::Subscriber;
use zenoh::sample::Sample;
use zenoh::{Session, Wait};

use crate::attachment;
use crate::batch;
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

/// How long after a topic's last sample one coming the other way (batch or per-topic key) with
/// a seq not after it counts as a repeat of the switch; later it is a restarted publisher.
const SWITCH_WINDOW: Duration = Duration::from_secs(1);
/// Topics whose way is remembered (a flood of keys costs no memory beyond this).
const MAX_WAYS: usize = 4096;

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

/// The way a topic's samples came last: through batches or not, the last seq, when.
struct Way {
    batched: bool,
    last: Option<u64>,
    at: Instant,
}

struct RuleState {
    topics: RwLock<HashMap<String, InTopic>>,
    closed: AtomicBool,
    on_sample: SampleFn,
    ctx: usize,
    fns: LnFns,
    logger: Logger,
    /// Set once the rule took batches: from then the ways of topics are followed.
    batches_seen: AtomicBool,
    ways: Ways,
    /// The remote's "P/topic/" and "P/batch/": a batch key's topic key.
    heads: Option<(String, String)>,
    remote: String,
    /// Malformed batches of topics not handed over (those count in the topic's counters).
    bad_batches: AtomicU64,
    complainer: Complainer,
}

/// The ways of a rule's topics, by topic key.
#[derive(Default)]
struct Ways(Mutex<HashMap<String, Way>>);

impl Ways {
    /// Whether a sample of `key` with `seq` coming `batched` (or not) at `now` is new, not a
    /// repeat of the switch; notes its way.
    fn is_new(&self, key: &str, seq: Option<u64>, batched: bool, now: Instant) -> bool {
        let mut ways = self.0.lock().unwrap_or_else(|e| e.into_inner());
        let full = ways.len() >= MAX_WAYS;
        match ways.get_mut(key) {
            Some(way) => {
                if way.batched != batched {
                    if let (Some(last), Some(seq)) = (way.last, seq) {
                        if seq <= last && now.duration_since(way.at) < SWITCH_WINDOW {
                            return false;
                        }
                    }
                    way.batched = batched;
                }
                way.last = seq.or(way.last);
                way.at = now;
            }
            None if !full => {
                ways.insert(key.to_string(), Way { batched, last: seq, at: now });
            }
            None => {}
        }
        true
    }
}

impl Ways {
    /// How many leading samples of a batch of `key` with these seqs are repeats of the switch
    /// (as is_new would say of each, at `now`); notes the way.
    fn batch_repeats(&self, key: &str, seqs: &[u64], now: Instant) -> usize {
        let mut ways = self.0.lock().unwrap_or_else(|e| e.into_inner());
        let full = ways.len() >= MAX_WAYS;
        let Some(&newest) = seqs.last() else { return 0 };
        match ways.get_mut(key) {
            Some(way) => {
                let mut skip = 0;
                if !way.batched {
                    if let Some(last) = way.last {
                        if now.duration_since(way.at) < SWITCH_WINDOW {
                            skip = seqs.iter().take_while(|&&seq| seq <= last).count();
                        }
                    }
                    if skip == seqs.len() {
                        return skip;
                    }
                    way.batched = true;
                }
                way.last = Some(newest);
                way.at = now;
                skip
            }
            None => {
                if !full {
                    ways.insert(key.to_string(), Way { batched: true, last: Some(newest), at: now });
                }
                0
            }
        }
    }
}

impl RuleState {
    fn is_new(&self, key: &str, seq: Option<u64>, batched: bool) -> bool {
        self.ways.is_new(key, seq, batched, Instant::now())
    }
}

/// The seq of a sample's attachment, if it has one at its place.
fn seq_of(att: Option<&[u8]>) -> Option<u64> {
    let a = att.filter(|a| a.len() >= 12)?;
    Some(u64::from_le_bytes(a[4..12].try_into().ok()?))
}

pub struct InRule {
    state: Arc<RuleState>,
    session: Session,
    key_expr: String,
    subscribers: Arc<Mutex<Subs>>,
}

/// The rule's subscriptions: one of them but during a switch (GRACE).
#[derive(Default)]
struct Subs {
    topics: Option<Subscriber<()>>,
    batches: Option<Subscriber<()>>,
    batched: bool, // batches wanted (set_batch)
    switch: u64,   // counts set_batch's switches: a later one cancels an earlier one's end
}

/// How long both subscriptions stay during a switch: the sender learns of the new one and
/// puts on both keys before the old one goes, so no sample falls between them.
const GRACE: Duration = Duration::from_millis(500);

impl InRule {
    /// `remote`: the prefix of the bridge whose batches the rule may take (set_batch), or None.
    pub fn open(session: &Session, key_expr: &str, remote: Option<&str>, fns: LnFns,
                logger: Logger, on_sample: SampleFn, ctx: usize) -> Result<InRule, String> {
        let heads = remote.map(|r| (format!("{r}/topic/"), format!("{r}/batch/")));
        let label = format!("batches from {}", remote.unwrap_or("?"));
        let state = Arc::new(RuleState { topics: RwLock::new(HashMap::new()),
                                         closed: AtomicBool::new(false), on_sample, ctx, fns,
                                         logger, batches_seen: AtomicBool::new(false),
                                         ways: Ways::default(), heads,
                                         remote: remote.unwrap_or("?").to_string(),
                                         bad_batches: AtomicU64::new(0),
                                         complainer: Complainer::new(logger, label) });
        let rule = InRule { state, session: session.clone(), key_expr: key_expr.to_string(),
                            subscribers: Arc::new(Mutex::new(Subs::default())) };
        let topic_sub = rule.subscribe_topics()?;
        rule.subscribers.lock().unwrap_or_else(|e| e.into_inner()).topics = Some(topic_sub);
        Ok(rule)
    }

    fn subscribe_topics(&self) -> Result<Subscriber<()>, String> {
        let st = self.state.clone();
        self.session.declare_subscriber(self.key_expr.clone())
            .callback(move |sample| on_sample_of(&st, &sample))
            .wait()
            .map_err(|e| format!("cannot subscribe to {}: {e}", self.key_expr))
    }

    /// The rule's key expression for batches: the remote's batch keys of the same names.
    fn batch_expr(&self) -> Option<String> {
        let (topic_head, batch_head) = self.state.heads.as_ref()?;
        Some(format!("{batch_head}{}", self.key_expr.strip_prefix(topic_head.as_str())?))
    }

    /// Takes the remote's batches instead of its per-topic samples (`on`), or back; the new
    /// subscription is declared at once, the old one goes GRACE later, so no sample is lost
    /// meanwhile (what comes both ways is dropped once: RuleState::is_new, batch_repeats).
    pub fn set_batch(&self, on: bool) -> Result<(), String> {
        let mut subs = self.subscribers.lock().unwrap_or_else(|e| e.into_inner());
        if self.state.closed.load(SeqCst) || on == subs.batched {
            return Ok(());
        }
        if on && subs.batches.is_none() {
            let expr = self.batch_expr()
                .ok_or_else(|| format!("no batch keys for {}", self.key_expr))?;
            self.state.batches_seen.store(true, SeqCst);
            let st = self.state.clone();
            subs.batches = Some(self.session.declare_subscriber(expr.clone())
                .callback(move |sample| on_batch_of(&st, &sample))
                .wait()
                .map_err(|e| format!("cannot subscribe to {expr}: {e}"))?);
        } else if !on && subs.topics.is_none() {
            subs.topics = Some(self.subscribe_topics()?);
        }
        subs.batched = on;
        subs.switch += 1;
        let (switch, shared) = (subs.switch, self.subscribers.clone());
        let (logger, remote) = (self.state.logger, self.state.remote.clone());
        std::thread::Builder::new()
            .name("lnz switch".into())
            .spawn(move || {
                std::thread::sleep(GRACE);
                let old = {
                    let mut subs = shared.lock().unwrap_or_else(|e| e.into_inner());
                    if subs.switch != switch {
                        return; // switched again meanwhile: that switch ends it
                    }
                    if on { subs.topics.take() } else { subs.batches.take() }
                };
                if let Some(sub) = old {
                    let _ = sub.undeclare().wait();
                }
                logger.say(&format!("topics from {remote}: samples come {}",
                                    if on { "in batches" } else { "one by one" }));
            })
            .map_err(|e| format!("cannot start a thread: {e}"))?;
        Ok(())
    }

    /// Malformed batches of topics not handed over (dropped).
    pub fn bad_batches(&self) -> u64 {
        self.state.bad_batches.load(Relaxed)
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
        let (topic_sub, batch_sub) = {
            let mut subs = self.subscribers.lock().unwrap_or_else(|e| e.into_inner());
            (subs.topics.take(), subs.batches.take())
        };
        for sub in [topic_sub, batch_sub].into_iter().flatten() {
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
    if state.batches_seen.load(Relaxed) && !state.is_new(key, seq_of(att.as_deref()), false) {
        return;
    }
    {
        let topics = state.topics.read().unwrap_or_else(|e| e.into_inner());
        if let Some(topic) = topics.get(key) {
            handle(&state.fns, topic, sample.payload(), att.as_deref());
            return;
        }
    }
    to_python(state, key, &sample.payload().to_bytes(), att.as_deref());
}

/// A sample of a key not handed over goes to the Python side.
fn to_python(state: &RuleState, key: &str, payload: &[u8], att: Option<&[u8]>) {
    if state.closed.load(SeqCst) {
        return;
    }
    let (att_ptr, att_len) = match att {
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

/// A batch: each sample in it is handled as one of the topic's per-topic key, in order.
fn on_batch_of(state: &RuleState, sample: &Sample) {
    if state.closed.load(SeqCst) {
        return;
    }
    let Some((topic_head, batch_head)) = &state.heads else { return };
    let Some(name) = sample.key_expr().as_str().strip_prefix(batch_head.as_str()) else { return };
    let key = format!("{topic_head}{name}");
    let att = sample.attachment().map(|a| a.to_bytes());
    let payload = sample.payload().to_bytes();
    let entries = match batch::decode(&payload) {
        Ok(entries) => entries,
        Err(why) => {
            bad_batch(state, &key, &why);
            return;
        }
    };
    let Some(att) = att.as_deref().filter(|a| a.len() >= attachment::HEAD_SIZE) else {
        bad_batch(state, &key, "no attachment to give its samples");
        return;
    };
    let seqs: Vec<u64> = entries.iter().map(|e| e.seq).collect();
    let skip = state.ways.batch_repeats(&key, &seqs, Instant::now());
    let entries = &entries[skip..];
    if entries.is_empty() {
        return;
    }
    {
        let topics = state.topics.read().unwrap_or_else(|e| e.into_inner());
        if let Some(topic) = topics.get(&key) {
            // the md is checked once for the batch: its samples share the attachment's
            let c = topic.counters.get();
            add(&c.batches, 1);
            add(&c.received, entries.len() as u64);
            if checked(topic, Some(att), entries.len() as u64).is_some() {
                for entry in entries {
                    publish(&state.fns, topic, entry.payload, entry.seq);
                }
            }
            return;
        }
    }
    // not handed over (yet): to Python, sample by sample; the topic may be handed over meanwhile
    let mut entry_att = Vec::with_capacity(att.len());
    for entry in entries {
        if !batch::entry_attachment(att, entry, &mut entry_att) {
            continue;
        }
        {
            let topics = state.topics.read().unwrap_or_else(|e| e.into_inner());
            if let Some(topic) = topics.get(&key) {
                handle(&state.fns, topic, entry.payload, Some(&entry_att));
                continue;
            }
        }
        to_python(state, &key, entry.payload, Some(&entry_att));
    }
}

/// Counts a malformed batch (the topic's counters, or the rule's if not handed over) and says
/// why, at most every 5 s; the batch is dropped, other topics go on.
fn bad_batch(state: &RuleState, key: &str, why: &str) {
    let topics = state.topics.read().unwrap_or_else(|e| e.into_inner());
    match topics.get(key) {
        Some(topic) => {
            add(&topic.counters.get().bad_batches, 1);
            topic.complainer.complain("batch", || {
                format!("batch dropped: {why} (counted as bad_batches)")
            });
        }
        None => {
            state.bad_batches.fetch_add(1, Relaxed);
            state.complainer.complain("batch", || {
                format!("batch of {key} dropped: {why} (counted as bad_batches)")
            });
        }
    }
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
    add(&topic.counters.get().received, 1);
    if let Some(seq) = checked(topic, att, 1) {
        publish(fns, topic, payload, seq);
    }
}

/// The seq of an attachment naming the topic's md, or None with `n` samples counted as
/// bad_attachment or refused (and said).
fn checked(topic: &InTopic, att: Option<&[u8]>, n: u64) -> Option<u64> {
    let c = topic.counters.get();
    let att = match attachment::decode(att) {
        Ok(a) => a,
        Err(why) => {
            add(&c.bad_attachment, n);
            topic.complainer.complain("attachment", || {
                format!("sample dropped: {why} (counted as bad_attachment)")
            });
            return None;
        }
    };
    if att.md_name != topic.md_name || att.layout_hash != topic.layout_hash {
        add(&c.refused, n);
        topic.complainer.complain("md", || {
            format!("sample of md '{}' 0x{:016x} dropped: this topic carries '{}' 0x{:016x}",
                    att.md_name, att.layout_hash, topic.md_name, topic.layout_hash)
        });
        return None;
    }
    Some(att.seq)
}

/// Checks a sample's size, counts gaps, applies the rate and writes it into the topic.
fn publish<P: Payload + ?Sized>(fns: &LnFns, topic: &InTopic, payload: &P, seq: u64) {
    let c = topic.counters.get();
    if payload.len() != topic.size {
        add(&c.bad_size, 1);
        topic.complainer.complain("size", || {
            format!("sample of {} bytes dropped: md '{}' has {} (counted as bad_size)",
                    payload.len(), topic.md_name, topic.size)
        });
        return;
    }
    let last = get(&c.last_seq);
    if last != 0 && seq > last + 1 {
        add(&c.gaps, seq - last - 1);
    }
    set(&c.last_seq, seq);
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_switch_drops_repeats_only() {
        let ways = Ways::default();
        let t0 = Instant::now();
        // per-topic samples 1..3, then the batch subscription: batches repeat 2..3, bring 4..
        assert!((1..=3).all(|seq| ways.is_new("k", Some(seq), false, t0)));
        assert!(!ways.is_new("k", Some(2), true, t0));
        assert!(!ways.is_new("k", Some(3), true, t0));
        assert!(ways.is_new("k", Some(4), true, t0));
        // the per-topic copies of what came in batches are repeats; then batches go on
        assert!(!ways.is_new("k", Some(4), false, t0));
        assert!(ways.is_new("k", Some(5), true, t0));
        // another topic is not touched
        assert!(ways.is_new("other", Some(1), true, t0));
        // a publisher restarted (seq from 1 again) on the same way is new
        assert!(ways.is_new("k", Some(1), true, t0));
        // and coming the other way after SWITCH_WINDOW, too
        let later = t0 + SWITCH_WINDOW + Duration::from_millis(1);
        assert!(ways.is_new("k", Some(1), false, later));
        // no seq (a malformed attachment, counted later): never taken for a repeat
        assert!(ways.is_new("k", None, true, later));
    }

    #[test]
    fn a_batch_skips_the_repeats_it_starts_with() {
        let ways = Ways::default();
        let t0 = Instant::now();
        assert!((1..=3).all(|seq| ways.is_new("k", Some(seq), false, t0)));
        assert_eq!(ways.batch_repeats("k", &[1, 2], t0), 2); // all repeats: nothing changes
        assert_eq!(ways.batch_repeats("k", &[2, 3, 4, 5], t0), 2);
        assert!(!ways.is_new("k", Some(5), false, t0)); // the per-topic copy of 5
        assert_eq!(ways.batch_repeats("k", &[6, 7], t0), 0);
        assert_eq!(ways.batch_repeats("new", &[1], t0), 0);
        // after SWITCH_WINDOW a per-topic sample is new whatever its seq, and so is a batch
        let later = t0 + SWITCH_WINDOW + Duration::from_millis(1);
        assert!(ways.is_new("k", Some(1), false, later));
        let much_later = later + SWITCH_WINDOW + Duration::from_millis(1);
        assert_eq!(ways.batch_repeats("k", &[1, 2], much_later), 0);
    }
}
