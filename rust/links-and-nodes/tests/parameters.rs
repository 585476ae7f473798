//! Parameter blocks against a real manager: values set and reset with `ln_manager param`
//! reach the program at its next update(), a value out of range is refused with the reason
//! and changes nothing, and the program's own input shows where there is no override.

mod common;

use common::{eventually, Manager};
use links_and_nodes::ParameterOptions;

fn tool_ok(manager: &Manager, args: &[&str]) -> String {
    let out = manager.tool(args);
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "ln_manager {args:?}: {text}");
    text
}

#[test]
fn overrides_of_the_manager_reach_the_loop_at_update() {
    let manager = Manager::start();
    let client = manager.client("rust_params");
    let mut block = client.parameter_block("gains").unwrap();
    let limits = ParameterOptions {
        description: Some("stiffness".into()),
        min: Some(0.0),
        max: Some(1000.0),
        read_only: false,
    };
    let kp = block
        .add::<f64>("kp", &[50.0, 30.0, 10.0], &limits)
        .unwrap();
    let mode = block.add::<i32>("mode", &[2], &Default::default()).unwrap();
    assert_eq!((kp.index(), mode.index(), kp.len()), (0, 1, 3));
    block.register().unwrap();
    assert_eq!(
        block.service_name().unwrap(),
        format!("{}.parameters.gains", client.name())
    );
    block.update().unwrap();
    assert_eq!(block.get(&kp), &[50.0, 30.0, 10.0]);
    assert_eq!(block.get(&mode), &[2]);

    let name = format!("{}.gains", client.name());
    tool_ok(
        &manager,
        &["param", "set", &name, "kp", "[200, 150, 5]", "mode", "7"],
    );
    let mut changed = 0;
    assert!(eventually(10, || {
        changed += block.update().unwrap();
        changed == 2
    }));
    assert_eq!(block.get(&kp), &[200.0, 150.0, 5.0]);
    assert_eq!(block.get(&mode), &[7]);

    // out of range: refused with the reason, nothing taken
    let out = manager.tool(&["param", "set", &name, "kp", "[5000, 1, 1]"]);
    let text =
        String::from_utf8_lossy(&out.stderr).to_string() + &String::from_utf8_lossy(&out.stdout);
    assert!(!out.status.success(), "{text}");
    assert!(text.contains("5000"), "{text}");
    assert_eq!(block.update().unwrap(), 0);
    assert_eq!(block.get(&kp), &[200.0, 150.0, 5.0]);

    // the input shows once the override is reset
    block.set_input(&kp, &[60.0, 40.0, 20.0]).unwrap();
    block.update().unwrap();
    assert_eq!(block.get(&kp), &[200.0, 150.0, 5.0], "the override wins");
    tool_ok(&manager, &["param", "reset", &name, "kp"]);
    assert!(eventually(10, || block.update().unwrap() == 1));
    assert!(block.changed(&kp));
    assert!(!block.changed(&mode));
    assert_eq!(block.get(&kp), &[60.0, 40.0, 20.0]);
    assert_eq!(block.get(&mode), &[7]);
    assert!(
        block.set_input(&kp, &[1.0]).is_err(),
        "element count checked"
    );
}

#[test]
fn the_validator_refuses_with_its_reason_and_a_panic_in_it_refuses_too() {
    let manager = Manager::start();
    let client = manager.client("rust_validator");
    let mut block = client.parameter_block("limits").unwrap();
    let speed = block
        .add::<f32>("speed", &[1.0, 0.5], &Default::default())
        .unwrap();
    let odd = block.add::<u16>("odd", &[1], &Default::default()).unwrap();
    block.set_validator(move |value| {
        if let Some(v) = value.get(&speed) {
            if v[0] < v[1] {
                return Err(format!("{}: must fall", value.name()));
            }
        }
        if let Some(v) = value.get(&odd) {
            assert!(v[0] % 2 == 1, "even");
        }
        Ok(())
    });
    block.register().unwrap();
    let name = format!("{}.limits", client.name());

    let out = manager.tool(&["param", "set", &name, "speed", "[0.25, 2]"]);
    let text =
        String::from_utf8_lossy(&out.stderr).to_string() + &String::from_utf8_lossy(&out.stdout);
    assert!(
        !out.status.success() && text.contains("speed: must fall"),
        "{text}"
    );
    let out = manager.tool(&["param", "set", &name, "odd", "4"]);
    let text =
        String::from_utf8_lossy(&out.stderr).to_string() + &String::from_utf8_lossy(&out.stdout);
    assert!(
        !out.status.success() && text.contains("the validator panicked"),
        "{text}"
    );

    tool_ok(
        &manager,
        &["param", "set", &name, "speed", "[3, 2]", "odd", "5"],
    );
    assert!(eventually(10, || block.update().unwrap() == 2));
    assert_eq!(block.get(&speed), &[3.0, 2.0]);
    assert_eq!(block.get(&odd), &[5]);
}
