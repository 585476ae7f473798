//! Closing a client: every handle of it then fails with ECLOSED instead of touching freed
//! memory, whether the client was closed explicitly or dropped first, and even while a
//! borrow of one of its ports is still held.

mod common;

use common::{Counter, Manager};
use links_and_nodes::{Error, Mode, PublisherOptions};

#[test]
fn reading_and_writing_after_close_fail_with_eclosed() {
    let manager = Manager::start();
    let client = manager.client("rust_close");
    let mut sub = client
        .subscribe::<Counter>("t.close", Mode::Latest)
        .unwrap();
    let mut publisher = client
        .publish::<Counter>("t.close", PublisherOptions::default())
        .unwrap();
    publisher.write(&Counter::default()).unwrap();
    client.close().unwrap();
    assert!(matches!(sub.read(0.0), Err(Error::ECLOSED(_))));
    assert!(matches!(sub.borrow(0.0), Err(Error::ECLOSED(_))));
    assert!(matches!(sub.overruns(), Err(Error::ECLOSED(_))));
    assert!(matches!(
        publisher.write(&Counter::default()),
        Err(Error::ECLOSED(_))
    ));
    assert!(matches!(publisher.loan(), Err(Error::ECLOSED(_))));
    assert_eq!(
        publisher.write(&Counter::default()).unwrap_err().name(),
        "ECLOSED"
    );
}

#[test]
fn dropping_the_client_first_closes_its_ports() {
    let manager = Manager::start();
    let client = manager.client("rust_drop");
    let mut sub = client.subscribe::<Counter>("t.drop", Mode::Latest).unwrap();
    let mut block = client.parameter_block("gains").unwrap();
    let kp = block.add::<f64>("kp", &[1.0], &Default::default()).unwrap();
    drop(client);
    assert!(matches!(sub.read(0.0), Err(Error::ECLOSED(_))));
    assert!(matches!(block.update(), Err(Error::ECLOSED(_))));
    assert_eq!(block.get(&kp), &[1.0]);
}

#[test]
fn closing_while_a_borrow_is_held_defers_the_destruction() {
    let manager = Manager::start();
    let client = manager.client("rust_close_borrow");
    let mut sub = client
        .subscribe::<Counter>("t.close_borrow", Mode::Queued(2))
        .unwrap();
    let mut publisher = client
        .publish::<Counter>("t.close_borrow", PublisherOptions::default())
        .unwrap();
    publisher
        .write(&Counter {
            count: 3,
            value: 1.5,
        })
        .unwrap();
    let borrowed = sub.borrow(5.0).unwrap().expect("a sample");
    client.close().unwrap(); // does not wait for the borrow, does not free under it
    let count = borrowed.read().count;
    assert_eq!(count, 3);
    borrowed.release().unwrap();
    assert!(matches!(sub.read(0.0), Err(Error::ECLOSED(_))));
    assert!(matches!(
        publisher.write(&Counter::default()),
        Err(Error::ECLOSED(_))
    ));
}
