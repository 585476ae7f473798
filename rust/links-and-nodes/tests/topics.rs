//! Topics against a real manager: latest and queued subscribers with exact values and
//! sequence numbers, loans sent and dropped, borrows, counts, a refused layout, a killed
//! publisher.

mod common;

use common::{eventually, Counter, CounterOther, Manager};
use links_and_nodes::{Error, Mode, PublisherOptions};

fn counter(count: u64) -> Counter {
    Counter {
        count,
        value: count as f64 * 0.25,
    }
}

#[test]
fn latest_subscriber_gets_the_newest_sample_once() {
    let manager = Manager::start();
    let client = manager.client("rust_latest");
    let mut sub = client
        .subscribe::<Counter>("t.latest", Mode::Latest)
        .unwrap();
    let mut publisher = client
        .publish::<Counter>("t.latest", PublisherOptions::default())
        .unwrap();
    for i in 1..=3 {
        publisher.write(&counter(i * 10)).unwrap();
    }
    let sample = sub.read(5.0).unwrap().expect("a sample");
    assert_eq!(*sample, counter(30));
    assert_eq!(sample.seq(), 3);
    assert!(sample.timestamp_ns() > 0);
    assert!(
        sub.read(0.0).unwrap().is_none(),
        "the sample was read already"
    );
    assert!(sub.read(0.05).unwrap().is_none());
    publisher.write(&counter(40)).unwrap();
    let sample = sub.read(5.0).unwrap().expect("a sample");
    assert_eq!((*sample, sample.seq()), (counter(40), 4));
}

#[test]
fn queued_subscriber_gets_every_sample_in_order_and_counts_what_it_lost() {
    let manager = Manager::start();
    let client = manager.client("rust_queued");
    let mut sub = client
        .subscribe::<Counter>("t.queued", Mode::Queued(8))
        .unwrap();
    let mut publisher = client
        .publish::<Counter>("t.queued", PublisherOptions::default())
        .unwrap();
    for i in 1..=5 {
        publisher.write(&counter(i)).unwrap();
    }
    for i in 1..=5 {
        let sample = sub.read(5.0).unwrap().expect("a sample");
        assert_eq!(
            (*sample, sample.seq(), sample.overruns()),
            (counter(i), i, 0)
        );
    }
    assert!(sub.read(0.0).unwrap().is_none());
    assert_eq!(sub.overruns().unwrap(), 0);

    // two buffers, twelve samples: the oldest are dropped and counted
    let mut small = client
        .subscribe::<Counter>("t.queued", Mode::Queued(2))
        .unwrap();
    for i in 6..=17 {
        publisher.write(&counter(i)).unwrap();
    }
    let (mut seen, mut lost, mut last) = (0, 0, 5);
    while let Some(sample) = small.read(0.0).unwrap() {
        assert!(sample.seq() > last, "sequence numbers rise");
        assert_eq!(*sample, counter(sample.seq()));
        last = sample.seq();
        seen += 1;
        lost += sample.overruns();
    }
    assert_eq!(last, 17);
    assert_eq!(seen + lost, 12);
    assert!(lost > 0);
    assert_eq!(small.overruns().unwrap(), lost);
}

#[test]
fn a_sent_loan_is_published_and_a_dropped_one_is_not() {
    let manager = Manager::start();
    let client = manager.client("rust_loan");
    let mut sub = client
        .subscribe::<Counter>("t.loan", Mode::Queued(4))
        .unwrap();
    let mut publisher = client
        .publish::<Counter>("t.loan", PublisherOptions::default())
        .unwrap();
    let mut loan = publisher.loan().unwrap();
    *loan = counter(7);
    loan.send().unwrap();
    let sample = sub.read(5.0).unwrap().expect("the sent loan");
    assert_eq!((*sample, sample.seq()), (counter(7), 1));

    let mut loan = publisher.loan().unwrap();
    loan.count = 99;
    drop(loan);
    assert!(
        sub.read(0.2).unwrap().is_none(),
        "a dropped loan publishes nothing"
    );
    publisher.write(&counter(8)).unwrap();
    let sample = sub.read(5.0).unwrap().expect("the next write");
    assert_eq!((*sample, sample.seq()), (counter(8), 2));
}

#[test]
fn a_borrowed_sample_is_read_in_place_and_released_intact() {
    let manager = Manager::start();
    let client = manager.client("rust_borrow");
    let mut sub = client
        .subscribe::<Counter>("t.borrow", Mode::Queued(4))
        .unwrap();
    let mut publisher = client
        .publish::<Counter>("t.borrow", PublisherOptions::default())
        .unwrap();
    publisher.write(&counter(5)).unwrap();
    publisher.write(&counter(6)).unwrap();
    let borrowed = sub.borrow(5.0).unwrap().expect("a sample");
    assert_eq!((borrowed.read(), borrowed.seq()), (counter(5), 1));
    // SAFETY: the publisher is idle while the reference is used.
    let in_place = unsafe { borrowed.get() }.count;
    assert_eq!(in_place, 5);
    borrowed.release().unwrap();
    let borrowed = sub.borrow(5.0).unwrap().expect("the second sample");
    assert_eq!((borrowed.read(), borrowed.seq()), (counter(6), 2));
    drop(borrowed);
    assert!(sub.borrow(0.0).unwrap().is_none());
}

#[test]
fn ports_count_each_other() {
    let manager = Manager::start();
    let client = manager.client("rust_counts");
    let publisher = client
        .publish::<Counter>("t.counts", PublisherOptions::default())
        .unwrap();
    assert_eq!(publisher.subscriber_count().unwrap(), 0);
    let sub = client
        .subscribe::<Counter>("t.counts", Mode::Latest)
        .unwrap();
    assert!(eventually(10, || publisher.subscriber_count().unwrap() == 1));
    assert_eq!(sub.publisher_count().unwrap(), 1);
    drop(sub);
    assert!(eventually(10, || publisher.subscriber_count().unwrap() == 0));
}

#[test]
fn another_layout_is_refused_with_both_md_names() {
    let manager = Manager::start();
    let client = manager.client("rust_layout");
    let _publisher = client
        .publish::<Counter>("t.layout", PublisherOptions::default())
        .unwrap();
    let err = client
        .subscribe::<CounterOther>("t.layout", Mode::Latest)
        .unwrap_err();
    assert!(matches!(err, Error::ELAYOUT(_)), "{err:?}");
    assert_eq!(err.name(), "ELAYOUT");
    let text = err.to_string();
    assert!(text.contains("rust_test/counter_other"), "{text}");
    assert!(
        text.replace("rust_test/counter_other", "")
            .contains("rust_test/counter"),
        "{text}"
    );
}

#[test]
fn a_killed_publisher_leaves_the_subscriber_without_samples_not_hanging() {
    let manager = Manager::start();
    let example = std::env::current_exe()
        .unwrap()
        .parent()
        .unwrap()
        .join("../examples/publish_counter");
    let mut child = std::process::Command::new(&example)
        .env("LN_MANAGER", &manager.address)
        .spawn()
        .unwrap_or_else(|e| panic!("{}: {e}", example.display()));
    let client = manager.client("rust_killed");
    let mut sub = client
        .subscribe::<Counter>("rust.counter", Mode::Latest)
        .unwrap();
    let first = sub
        .read(20.0)
        .unwrap()
        .expect("a sample of the example")
        .seq();
    child.kill().unwrap();
    child.wait().unwrap();
    // whatever was in flight, then nothing: a read with a timeout returns
    let mut last = first;
    while let Some(sample) = sub.read(1.0).unwrap() {
        assert!(sample.seq() > last);
        last = sample.seq();
    }
    assert!(sub.read(0.5).unwrap().is_none());
    assert!(eventually(15, || sub.publisher_count().unwrap() == 0));
}
