//! Publishes a counter on topic "rust.counter" ten times a second: the smallest program of
//! the safe API.  Run it under a manager (`LN_MANAGER=HOST:PORT` or `-ln_manager HOST:PORT`).

use links_and_nodes::{Client, Message, PublisherOptions};

/// md "rust_test/counter" (tests/md/rust_test/counter): `uint64_t count`, `double value`.
#[repr(C, packed)]
#[derive(Clone, Copy, Default)]
struct Counter {
    count: u64,
    value: f64,
}

// SAFETY: packed fields of md rust_test/counter in order; every bit pattern is valid.
unsafe impl Message for Counter {
    const MD_NAME: &'static str = "rust_test/counter";
    const LAYOUT_HASH: u64 = 0x1bede26f575983fc; // ln_generate's RUST_TEST_COUNTER_LAYOUT_HASH
}

fn main() -> links_and_nodes::Result<()> {
    let client = Client::new("rust_counter")?;
    let mut publisher = client.publish::<Counter>("rust.counter", PublisherOptions::default())?;
    for count in 0.. {
        publisher.write(&Counter {
            count,
            value: count as f64 * 0.5,
        })?;
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    Ok(())
}
