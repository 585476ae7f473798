//! lat_rust: ping-pong latency through two topics with links_and_nodes' safe Rust API, the
//! Rust twin of bench/topics/lat_ln.c (same arguments and output).  copy: `write`/`read` of
//! the whole sample; zc: `loan`/`send` and `borrow`/`release` touching the first and last
//! 8 bytes (as lat_ln zc); full: zero-copy moving the whole sample (see PayloadMode::Full).

use links_and_nodes::{Client, Mode, Publisher, PublisherOptions, Subscriber};
use ln_rust_bench::{
    fail, ping_loop, pong_loop, print_faults, ready, with_big_stack, write_samples, Args,
    BenchSample, PayloadMode, Sample1m, Sample4k, Sample4m, Sample64,
};

const WHO: &str = "lat_rust";

fn main() {
    let args = Args::parse();
    with_big_stack(move || match args.size {
        64 => run::<Sample64>(&args),
        4096 => run::<Sample4k>(&args),
        0x10_0000 => run::<Sample1m>(&args),
        0x40_0000 => run::<Sample4m>(&args),
        n => fail(
            "size",
            format!("no benchmark md of {n} bytes (64, 4096, 1 and 4 MiB)"),
        ),
    });
}

struct Ends<T: BenchSample> {
    publisher: Publisher<T>,
    subscriber: Subscriber<T>,
    mode: PayloadMode,
}

fn run<T: BenchSample + Default>(args: &Args) {
    let (out, inp) = args.topics();
    let name = if args.ping {
        "lat_rust_ping"
    } else {
        "lat_rust_pong"
    };
    let client = Client::new(name).unwrap_or_else(|e| fail("Client::new", e));
    let mut ends = Ends::<T> {
        publisher: client
            .publish(&out, PublisherOptions::default())
            .unwrap_or_else(|e| fail("publish", e)),
        subscriber: client
            .subscribe(&inp, Mode::Latest)
            .unwrap_or_else(|e| fail("subscribe", e)),
        mode: args.mode,
    };
    if !args.ping {
        ready();
        let faults = pong_loop(args.count, args.warmup, || ends.echo());
        print_faults(faults, args.count.saturating_sub(args.warmup));
        return;
    }
    let mut buf = Box::new(T::default());
    let mut reply = Box::new(T::default());
    let (rtt, faults) = ping_loop(args.count, args.warmup, |i| {
        ends.send(&mut buf, i);
        ends.receive(&mut reply)
    });
    print_faults(faults, args.count);
    write_samples(&args.out, &rtt);
    drop(ends);
    drop(client);
}

impl<T: BenchSample> Ends<T> {
    /// Sends sample `i` (copy and full: from `buf`).
    fn send(&mut self, buf: &mut T, i: u64) {
        match self.mode {
            PayloadMode::Copy => {
                buf.set_counter(i);
                self.publisher
                    .write(buf)
                    .unwrap_or_else(|e| fail("write", e));
            }
            PayloadMode::Zc => {
                let mut loan = self.publisher.loan().unwrap_or_else(|e| fail("loan", e));
                loan.stamp(i);
                loan.send().unwrap_or_else(|e| fail("send", e));
            }
            PayloadMode::Full => {
                buf.stamp(i);
                let mut loan = self.publisher.loan().unwrap_or_else(|e| fail("loan", e));
                *loan = *buf;
                loan.send().unwrap_or_else(|e| fail("send", e));
            }
        }
    }

    /// Receives one sample and returns its counter (full: copied whole into `reply`).
    fn receive(&mut self, reply: &mut T) -> u64 {
        match self.mode {
            PayloadMode::Copy => {
                let sample = self.subscriber.read(-1.0);
                let sample = sample.unwrap_or_else(|e| fail("read", e));
                sample
                    .unwrap_or_else(|| fail("read", "no sample"))
                    .counter()
            }
            PayloadMode::Zc | PayloadMode::Full => {
                let borrowed = self.subscriber.borrow(-1.0);
                let borrowed = borrowed.unwrap_or_else(|e| fail("borrow", e));
                let borrowed = borrowed.unwrap_or_else(|| fail("borrow", "no sample"));
                // SAFETY: the pong publishes the next sample only after this round trip.
                let data = unsafe { borrowed.get() };
                let counter = if self.mode == PayloadMode::Zc {
                    data.check(WHO)
                } else {
                    *reply = *data;
                    0
                };
                borrowed.release().unwrap_or_else(|e| fail("release", e));
                if self.mode == PayloadMode::Zc {
                    counter
                } else {
                    reply.check(WHO)
                }
            }
        }
    }

    /// Sends the next sample straight back.
    fn echo(&mut self) {
        if self.mode == PayloadMode::Copy {
            let sample = self.subscriber.read(-1.0);
            let sample = sample.unwrap_or_else(|e| fail("read", e));
            let sample = sample.unwrap_or_else(|| fail("read", "no sample"));
            self.publisher
                .write(&sample)
                .unwrap_or_else(|e| fail("write", e));
            return;
        }
        let borrowed = self.subscriber.borrow(-1.0);
        let borrowed = borrowed.unwrap_or_else(|e| fail("borrow", e));
        let borrowed = borrowed.unwrap_or_else(|| fail("borrow", "no sample"));
        // SAFETY: the ping publishes the next sample only after this one came back.
        let data = unsafe { borrowed.get() };
        if self.mode == PayloadMode::Zc {
            let counter = data.check(WHO);
            let mut loan = self.publisher.loan().unwrap_or_else(|e| fail("loan", e));
            borrowed.release().unwrap_or_else(|e| fail("release", e));
            loan.stamp(counter);
            loan.send().unwrap_or_else(|e| fail("send", e));
        } else {
            let mut loan = self.publisher.loan().unwrap_or_else(|e| fail("loan", e));
            *loan = *data;
            borrowed.release().unwrap_or_else(|e| fail("release", e));
            loan.check(WHO);
            loan.send().unwrap_or_else(|e| fail("send", e));
        }
    }
}
