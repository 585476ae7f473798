//! lat_iox2: ping-pong latency through two iceoryx2 publish-subscribe services (`[u8]`
//! payloads of SIZE bytes), with lat_ln's arguments, output and payload modes: copy (the
//! sample is written from the side's own buffer and copied out into it), zc (first and last
//! 8 bytes only) and full (the whole payload copied into the loan; the echo copies the whole
//! received payload into its loan).  iceoryx2's publish-subscribe has no blocking receive:
//! a side waiting for a sample polls `receive()` with `sched_yield` in between.

use std::mem::MaybeUninit;

use iceoryx2::prelude::*;
use iceoryx2::sample::Sample;
use ln_rust_bench::{
    check_bytes, fail, first_u64, ping_loop, pong_loop, print_faults, ready, stamp_bytes,
    write_samples, Args, PayloadMode,
};

const WHO: &str = "lat_iox2";

type Pub = iceoryx2::port::publisher::Publisher<ipc::Service, [u8], ()>;
type Sub = iceoryx2::port::subscriber::Subscriber<ipc::Service, [u8], ()>;

struct Ends {
    publisher: Pub,
    subscriber: Sub,
    size: usize,
    mode: PayloadMode,
}

fn main() {
    let args = Args::parse();
    if args.size < 16 {
        fail("size", "at least 16 bytes");
    }
    set_log_level(LogLevel::Error);
    let node = NodeBuilder::new()
        .create::<ipc::Service>()
        .unwrap_or_else(|e| fail("node", e));
    let (out, inp) = args.topics();
    let service = |name: &str| {
        let name: ServiceName = name.try_into().unwrap_or_else(|e| fail("service name", e));
        node.service_builder(&name)
            .publish_subscribe::<[u8]>()
            .max_publishers(1)
            .max_subscribers(1)
            .history_size(0)
            .subscriber_max_buffer_size(1)
            .subscriber_max_borrowed_samples(1)
            .open_or_create()
            .unwrap_or_else(|e| fail("publish_subscribe", e))
    };
    let (out_service, in_service) = (service(&out), service(&inp));
    let ends = Ends {
        publisher: out_service
            .publisher_builder()
            .initial_max_slice_len(args.size)
            .max_loaned_samples(1)
            .create()
            .unwrap_or_else(|e| fail("publisher", e)),
        subscriber: in_service
            .subscriber_builder()
            .create()
            .unwrap_or_else(|e| fail("subscriber", e)),
        size: args.size,
        mode: args.mode,
    };
    let mut buf = vec![0x5au8; args.size];
    if !args.ping {
        ready();
        let faults = pong_loop(args.count, args.warmup, || ends.echo(&mut buf));
        print_faults(faults, args.count.saturating_sub(args.warmup));
        return;
    }
    let mut reply = vec![0x5au8; args.size];
    let (rtt, faults) = ping_loop(args.count, args.warmup, |i| {
        ends.send(&mut buf, i);
        ends.receive(&mut reply)
    });
    print_faults(faults, args.count);
    write_samples(&args.out, &rtt);
}

/// bench_stamp into an uninitialized loan: the first and last 8 bytes.
fn stamp_uninit(payload: &mut [MaybeUninit<u8>], value: u64) {
    let n = payload.len();
    let bytes = value.to_ne_bytes();
    for (dst, src) in payload[..8].iter_mut().zip(bytes) {
        dst.write(src);
    }
    for (dst, src) in payload[n - 8..].iter_mut().zip(bytes) {
        dst.write(src);
    }
}

impl Ends {
    fn wait(&self) -> Sample<ipc::Service, [u8], ()> {
        loop {
            match self.subscriber.receive() {
                Ok(Some(sample)) => return sample,
                Ok(None) => std::thread::yield_now(),
                Err(e) => fail("receive", e),
            }
        }
    }

    /// Publishes `bytes` copied whole into a loan.
    fn send_copy(&self, bytes: &[u8]) {
        let loan = self.publisher.loan_slice_uninit(self.size);
        let loan = loan.unwrap_or_else(|e| fail("loan_slice_uninit", e));
        loan.write_from_slice(bytes)
            .send()
            .unwrap_or_else(|e| fail("send", e));
    }

    /// Publishes a loan of which only the first and last 8 bytes are written.
    fn send_stamp(&self, value: u64) {
        let loan = self.publisher.loan_slice_uninit(self.size);
        let mut loan = loan.unwrap_or_else(|e| fail("loan_slice_uninit", e));
        stamp_uninit(loan.payload_mut(), value);
        // SAFETY: as lat_ln zc, the sample carries only its first and last 8 bytes; the rest
        // is the chunk's old content, which nobody reads (u8 has no invalid values).
        let loan = unsafe { loan.assume_init() };
        loan.send().unwrap_or_else(|e| fail("send", e));
    }

    fn send(&self, buf: &mut [u8], i: u64) {
        match self.mode {
            PayloadMode::Copy => {
                buf[..8].copy_from_slice(&i.to_ne_bytes());
                self.send_copy(buf);
            }
            PayloadMode::Zc => self.send_stamp(i),
            PayloadMode::Full => {
                stamp_bytes(buf, i);
                self.send_copy(buf);
            }
        }
    }

    fn receive(&self, reply: &mut [u8]) -> u64 {
        let sample = self.wait();
        match self.mode {
            PayloadMode::Copy => {
                reply.copy_from_slice(sample.payload());
                drop(sample);
                first_u64(reply)
            }
            PayloadMode::Zc => check_bytes(sample.payload(), WHO),
            PayloadMode::Full => {
                reply.copy_from_slice(sample.payload());
                drop(sample);
                check_bytes(reply, WHO)
            }
        }
    }

    fn echo(&self, buf: &mut [u8]) {
        let sample = self.wait();
        match self.mode {
            PayloadMode::Copy => {
                buf.copy_from_slice(sample.payload());
                drop(sample);
                self.send_copy(buf);
            }
            PayloadMode::Zc => {
                let counter = check_bytes(sample.payload(), WHO);
                let loan = self.publisher.loan_slice_uninit(self.size);
                let mut loan = loan.unwrap_or_else(|e| fail("loan_slice_uninit", e));
                drop(sample);
                stamp_uninit(loan.payload_mut(), counter);
                // SAFETY: as in send_stamp.
                let loan = unsafe { loan.assume_init() };
                loan.send().unwrap_or_else(|e| fail("send", e));
            }
            PayloadMode::Full => {
                let loan = self.publisher.loan_slice_uninit(self.size);
                let loan = loan.unwrap_or_else(|e| fail("loan_slice_uninit", e));
                let loan = loan.write_from_slice(sample.payload());
                drop(sample);
                check_bytes(loan.payload(), WHO);
                loan.send().unwrap_or_else(|e| fail("send", e));
            }
        }
    }
}
