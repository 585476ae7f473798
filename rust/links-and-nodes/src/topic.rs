//! Topics: typed [`Publisher`]s (copying `write` and zero-copy [`Loan`]) and [`Subscriber`]s
//! (copying `read` into a [`Sample`] and zero-copy [`Borrowed`]) over ln.h's ports.
//!
//! Threads (ln.h): ln_write, ln_read and the zero-copy calls from any thread, one thread per
//! port at a time; a loan is committed or aborted on the thread that took it.  So ports are
//! `Send` (move one to its thread) but not `Sync` (their calls take `&mut self`), and a
//! `Loan` or `Borrowed` is neither: it lives and dies on the thread that took it.

use std::ffi::{c_int, c_void};
use std::marker::PhantomData;
use std::mem::{size_of, MaybeUninit};
use std::ops::{Deref, DerefMut};
use std::ptr;
use std::sync::Arc;

use crate::client::{cstring, Open, Shared};
use crate::error::Result;
use crate::{check, sys, Client, Message};

/// How a subscriber sees the topic's samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Always the newest sample not read yet (one buffer).
    Latest,
    /// Every sample while at most `n` (2..=1024) behind; older ones are dropped and counted
    /// as overruns.
    Queued(u32),
}

/// Options of [`Client::publish`].
#[derive(Debug, Clone, Copy)]
pub struct PublisherOptions {
    /// `LN_PUBLISH_WAIT_FOR_SUBSCRIBERS`: a write waits (up to `timeout`) while a queued
    /// subscriber has no free buffer, instead of dropping that subscriber's oldest sample.
    pub wait_for_subscribers: bool,
    /// Seconds `write` and `loan` wait at most (< 0: forever); they wait only with
    /// `wait_for_subscribers` or while another publisher of the topic holds a loan.
    pub timeout: f64,
}

impl Default for PublisherOptions {
    fn default() -> Self {
        PublisherOptions {
            wait_for_subscribers: false,
            timeout: -1.0,
        }
    }
}

fn port_options() -> sys::ln_port_options {
    let mut opts = sys::ln_port_options::default();
    // SAFETY: fills the struct it is given.
    unsafe { sys::ln_port_options_init(&mut opts) };
    opts
}

impl Client {
    /// Publishes `topic` with samples of `T` (its md name, layout hash and size).  A topic
    /// has one layout: another one is refused with `Error::ELAYOUT`.
    pub fn publish<T: Message>(
        &self,
        topic: &str,
        options: PublisherOptions,
    ) -> Result<Publisher<T>> {
        let c_topic = cstring("topic", topic)?;
        let c_md = cstring("md name", T::MD_NAME)?;
        let mut opts = port_options();
        if options.wait_for_subscribers {
            opts.flags |= sys::LN_PUBLISH_WAIT_FOR_SUBSCRIBERS;
        }
        let mut port = ptr::null_mut();
        let (open, _setup) = self.shared().enter_setup()?;
        // SAFETY: the client is open (gate) and setup calls are serialized (_setup).
        check(unsafe {
            sys::ln_publish(
                open.raw(),
                &mut port,
                c_topic.as_ptr(),
                c_md.as_ptr(),
                T::LAYOUT_HASH,
                size_of::<T>(),
                &opts,
            )
        })?;
        Ok(Publisher {
            shared: Arc::clone(self.shared()),
            port,
            timeout: options.timeout,
            topic: topic.to_string(),
            _type: PhantomData,
        })
    }

    /// Subscribes to `topic` with samples of `T`; `Error::ELAYOUT` if the topic has another
    /// layout.
    pub fn subscribe<T: Message>(&self, topic: &str, mode: Mode) -> Result<Subscriber<T>> {
        let c_topic = cstring("topic", topic)?;
        let c_md = cstring("md name", T::MD_NAME)?;
        let mut opts = port_options();
        opts.buffers = match mode {
            Mode::Latest => 1,
            Mode::Queued(n) => n,
        };
        let mut port = ptr::null_mut();
        let (open, _setup) = self.shared().enter_setup()?;
        // SAFETY: as in publish.
        check(unsafe {
            sys::ln_subscribe(
                open.raw(),
                &mut port,
                c_topic.as_ptr(),
                c_md.as_ptr(),
                T::LAYOUT_HASH,
                size_of::<T>(),
                &opts,
            )
        })?;
        Ok(Subscriber {
            shared: Arc::clone(self.shared()),
            port,
            buffer: Box::new_uninit(),
            topic: topic.to_string(),
        })
    }
}

/// A sample and what a read returns with it.
#[derive(Debug, Clone, Copy)]
pub struct Sample<D> {
    data: D,
    info: sys::ln_sample_info,
}

impl<D> Sample<D> {
    /// The sample's data.
    pub fn data(&self) -> &D {
        &self.data
    }
    /// The topic's publish sequence number, from 1.
    pub fn seq(&self) -> u64 {
        self.info.seq
    }
    /// When it was published (CLOCK_REALTIME, ns since the epoch).
    pub fn timestamp_ns(&self) -> i64 {
        self.info.timestamp_ns
    }
    /// Samples this subscriber lost since its previous read.
    pub fn overruns(&self) -> u64 {
        self.info.overruns
    }
}

impl<T> Deref for Sample<&T> {
    type Target = T;
    fn deref(&self) -> &T {
        self.data
    }
}

/// A publisher of one topic.  `Send`, not `Sync`.  Dropping it unpublishes.
pub struct Publisher<T: Message> {
    shared: Arc<Shared>,
    port: *mut sys::ln_outport,
    timeout: f64,
    topic: String,
    _type: PhantomData<fn(T)>,
}

// SAFETY: ln.h allows a port's ln_write and zero-copy calls from any thread, one at a time
// (`&mut self`); the port lives as long as its client, kept by `shared`.
unsafe impl<T: Message> Send for Publisher<T> {}

impl<T: Message> Publisher<T> {
    /// The topic's name.
    pub fn topic(&self) -> &str {
        &self.topic
    }

    /// Copies `msg` into the topic.
    pub fn write(&mut self, msg: &T) -> Result<()> {
        let _open = self.shared.enter()?;
        // SAFETY: the port is open (gate); msg is size_of::<T>() readable bytes.
        check(unsafe {
            sys::ln_write(
                self.port,
                (msg as *const T).cast(),
                size_of::<T>(),
                self.timeout,
            )
        })
        .map(|_| ())
    }

    /// Lends the next slot of the topic's ring: fill it through the loan, then
    /// [`Loan::send`] publishes it; a loan dropped without `send` publishes nothing.  Other
    /// publishers of the topic wait meanwhile.  The slot holds stale bytes of an older
    /// sample, not zeros: write every field.
    pub fn loan(&mut self) -> Result<Loan<'_, T>> {
        let open = self.shared.enter()?;
        let mut data: *mut c_void = ptr::null_mut();
        // SAFETY: the port is open (gate, held by the loan until commit or abort).
        check(unsafe { sys::ln_write_loan(self.port, &mut data, self.timeout) })?;
        Ok(Loan {
            port: self.port,
            data: data.cast(),
            done: false,
            _open: open,
            _type: PhantomData,
        })
    }

    /// How many subscribers the topic has.
    pub fn subscriber_count(&self) -> Result<usize> {
        let _open = self.shared.enter()?;
        // SAFETY: the port is open (gate).
        check(unsafe { sys::ln_outport_subscriber_count(self.port) }).map(|n| n as usize)
    }
}

impl<T: Message> Drop for Publisher<T> {
    fn drop(&mut self) {
        if let Ok((_open, _setup)) = self.shared.enter_setup() {
            // SAFETY: the port is open and dropped once; setup calls serialized.
            unsafe { sys::ln_unpublish(self.port) };
        }
    }
}

/// A slot of the ring lent by [`Publisher::loan`]: `DerefMut` to `T`, published by
/// [`Loan::send`], discarded when dropped.  Neither `Send` nor `Sync` (ln.h: commit or
/// abort on the thread that took the loan).
pub struct Loan<'a, T: Message> {
    port: *mut sys::ln_outport,
    data: *mut T,
    done: bool,
    _open: Open<'a>,
    _type: PhantomData<&'a mut T>,
}

impl<T: Message> Loan<'_, T> {
    /// Publishes the slot.
    pub fn send(mut self) -> Result<()> {
        self.done = true;
        // SAFETY: the loan is open on this thread; the client is held open by `_open`.
        check(unsafe { sys::ln_write_commit(self.port) }).map(|_| ())
    }
}

impl<T: Message> Deref for Loan<'_, T> {
    type Target = T;
    fn deref(&self) -> &T {
        // SAFETY: the slot is ours until commit/abort; `T` is packed (align 1) and any bits
        // are a valid `T` (Message's contract).
        unsafe { &*self.data }
    }
}

impl<T: Message> DerefMut for Loan<'_, T> {
    fn deref_mut(&mut self) -> &mut T {
        // SAFETY: as in deref; the loan is exclusive to this publisher until commit/abort.
        unsafe { &mut *self.data }
    }
}

impl<T: Message> Drop for Loan<'_, T> {
    fn drop(&mut self) {
        if !self.done {
            // SAFETY: the loan is open on this thread (Loan is !Send).
            unsafe { sys::ln_write_abort(self.port) };
        }
    }
}

/// A subscriber of one topic.  `Send`, not `Sync`.  Dropping it unsubscribes.
pub struct Subscriber<T: Message> {
    shared: Arc<Shared>,
    port: *mut sys::ln_inport,
    // on the heap: a message may be larger than a thread's stack (16 MiB images)
    buffer: Box<MaybeUninit<T>>,
    topic: String,
}

// SAFETY: ln.h allows a port's ln_read and zero-copy calls from any thread, one at a time
// (`&mut self`); the port lives as long as its client, kept by `shared`.
unsafe impl<T: Message> Send for Subscriber<T> {}

/// Ok(false) for "no sample within the timeout" (EAGAIN, ETIMEOUT), without allocating.
fn got_sample(rc: c_int) -> Result<bool> {
    if rc == sys::LN_EAGAIN || rc == sys::LN_ETIMEOUT {
        Ok(false)
    } else {
        check(rc).map(|_| true)
    }
}

impl<T: Message> Subscriber<T> {
    /// The topic's name.
    pub fn topic(&self) -> &str {
        &self.topic
    }

    /// The next sample (latest: the newest not read yet; queued: the oldest unread), copied
    /// into the subscriber; `Ok(None)` if none came within `timeout` seconds (0: do not
    /// wait, < 0: forever).  Allocates nothing unless it fails.
    pub fn read(&mut self, timeout: f64) -> Result<Option<Sample<&T>>> {
        let open = self.shared.enter()?;
        let mut info = sys::ln_sample_info::default();
        // SAFETY: the port is open (gate); the buffer has size_of::<T>() bytes.
        let rc = unsafe {
            sys::ln_read(
                self.port,
                self.buffer.as_mut_ptr().cast(),
                size_of::<T>(),
                timeout,
                &mut info,
            )
        };
        drop(open);
        if !got_sample(rc)? {
            return Ok(None);
        }
        // SAFETY: ln_read filled all size_of::<T>() bytes; any bits are a valid T.
        let data = unsafe { self.buffer.assume_init_ref() };
        Ok(Some(Sample { data, info }))
    }

    /// Zero-copy read: the next sample stays in the topic's ring, lent until the returned
    /// guard is released (or dropped).  `Ok(None)` as for [`Subscriber::read`].
    pub fn borrow(&mut self, timeout: f64) -> Result<Option<Borrowed<'_, T>>> {
        let open = self.shared.enter()?;
        let mut info = sys::ln_sample_info::default();
        let mut data: *const c_void = ptr::null();
        // SAFETY: the port is open (gate, held by the guard until release).
        let rc = unsafe { sys::ln_read_borrow(self.port, &mut data, timeout, &mut info) };
        if !got_sample(rc)? {
            return Ok(None);
        }
        Ok(Some(Borrowed {
            port: self.port,
            data: data.cast(),
            info,
            released: false,
            _open: open,
            _type: PhantomData,
        }))
    }

    /// How many publishers the topic has.
    pub fn publisher_count(&self) -> Result<usize> {
        let _open = self.shared.enter()?;
        // SAFETY: the port is open (gate).
        check(unsafe { sys::ln_inport_publisher_count(self.port) }).map(|n| n as usize)
    }

    /// Samples this subscriber lost since it subscribed.
    pub fn overruns(&self) -> Result<u64> {
        let _open = self.shared.enter()?;
        // SAFETY: the port is open (gate).
        Ok(unsafe { sys::ln_inport_overruns(self.port) })
    }
}

impl<T: Message> Drop for Subscriber<T> {
    fn drop(&mut self) {
        if let Ok((_open, _setup)) = self.shared.enter_setup() {
            // SAFETY: the port is open and dropped once; setup calls serialized.
            unsafe { sys::ln_unsubscribe(self.port) };
        }
    }
}

/// A sample lent from the ring by [`Subscriber::borrow`] until [`Borrowed::release`] (or
/// drop).  A publisher may overwrite the slot meanwhile when the ring wraps around;
/// `release` then reports `Error::EOVERRUN`.  Because of that the data is offered as a copy
/// ([`Borrowed::read`]) or, unsafely, as a reference ([`Borrowed::get`]).  Neither `Send`
/// nor `Sync`.
pub struct Borrowed<'a, T: Message> {
    port: *mut sys::ln_inport,
    data: *const T,
    info: sys::ln_sample_info,
    released: bool,
    _open: Open<'a>,
    _type: PhantomData<&'a T>,
}

impl<T: Message> Borrowed<'_, T> {
    /// The topic's publish sequence number, from 1.
    pub fn seq(&self) -> u64 {
        self.info.seq
    }
    /// When it was published (CLOCK_REALTIME, ns since the epoch).
    pub fn timestamp_ns(&self) -> i64 {
        self.info.timestamp_ns
    }
    /// Samples this subscriber lost since its previous read.
    pub fn overruns(&self) -> u64 {
        self.info.overruns
    }

    /// A copy of the sample as it is in the ring now (check `release` for its integrity).
    pub fn read(&self) -> T {
        // SAFETY: data points at size_of::<T>() bytes of the ring while borrowed; a volatile
        // read, as a publisher in another process may write them; any bits are a valid T.
        unsafe { ptr::read_volatile(self.data) }
    }

    /// The sample in place, without a copy.
    ///
    /// # Safety
    ///
    /// The caller ensures no publisher can reach this slot while the reference is used
    /// (enough buffers for the publishing rate, or the publisher known to be idle); a value
    /// read while a publisher overwrote it is detected by `release` (EOVERRUN) only.
    pub unsafe fn get(&self) -> &T {
        &*self.data
    }

    /// Gives the slot back: `Ok` if the sample stayed intact while borrowed,
    /// `Error::EOVERRUN` if a publisher overwrote it meanwhile.
    pub fn release(mut self) -> Result<()> {
        self.released = true;
        // SAFETY: the borrow is open; the client is held open by `_open`.
        check(unsafe { sys::ln_read_release(self.port) }).map(|_| ())
    }
}

impl<T: Message> Drop for Borrowed<'_, T> {
    fn drop(&mut self) {
        if !self.released {
            // SAFETY: as in release.
            unsafe { sys::ln_read_release(self.port) };
        }
    }
}

impl<T: Message> std::fmt::Debug for Publisher<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Publisher({:?}, {})", self.topic, T::MD_NAME)
    }
}

impl<T: Message> std::fmt::Debug for Subscriber<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Subscriber({:?}, {})", self.topic, T::MD_NAME)
    }
}
