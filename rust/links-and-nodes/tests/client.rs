//! Connecting: the manager named by `-ln_manager HOST:PORT` in argv (as C and Python
//! clients find it), the name the manager gives, a control command, and a manager that is
//! not there.

mod common;

use common::Manager;
use links_and_nodes::{Client, ClientOptions, Error};

#[test]
fn the_manager_is_found_through_ln_manager_in_argv() {
    let manager = Manager::start();
    let options = ClientOptions {
        argv: Some(vec![
            "prog".into(),
            "-ln_manager".into(),
            manager.address.clone(),
        ]),
        timeout: Some(10.0),
        ..Default::default()
    };
    let client = Client::with_options("rust_argv", &options).unwrap();
    assert!(client.name().starts_with("rust_argv"), "{}", client.name());
    let second = Client::with_options("rust_argv", &options).unwrap();
    assert_ne!(
        second.name(),
        client.name(),
        "the manager makes names unique"
    );
    let answer = client.control(r#"{"op": "no_such_op"}"#);
    assert!(answer.is_err(), "{answer:?}");
}

#[test]
fn no_manager_is_a_connection_error_with_the_address() {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let address = format!("127.0.0.1:{}", listener.local_addr().unwrap().port());
    drop(listener); // a port nobody listens on
    let options = ClientOptions {
        manager: Some(address.clone()),
        argv: Some(Vec::new()),
        timeout: Some(2.0),
        no_reconnect: true,
    };
    let err = Client::with_options("rust_nobody", &options).unwrap_err();
    assert!(matches!(err, Error::ECONNECTION(_)), "{err:?}");
    assert!(err.to_string().contains(&address), "{err}");
}
