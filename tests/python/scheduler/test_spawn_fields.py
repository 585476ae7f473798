"""How a configured process becomes a SPAWN request (spawning.spawn_fields): the fields
whose shape differs are converted, every other SPAWN field of the schema is taken from the
process's attribute of the same name, so a key the daemon applies needs no scheduler line."""

from __future__ import annotations

import dataclasses

from links_and_nodes.manager.config import model
from links_and_nodes.manager.processes import spawning as sched
from links_and_nodes.manager.processes.daemon_wire import SpawnSpec


def _proc(**kw: object) -> model.Process:
    return model.Process(name="ctl", location=model.Location("t.lnc", 1, 1), command="ctl --rate 'a b'", node="localhost",
                         argv=["ctl", "--rate", "a b"], **kw)  # type: ignore[arg-type]


def test_a_configured_process_becomes_its_spawn_spec() -> None:
    p = _proc(priority=5, affinity=[1], max_output_lines=77, term_signal=2, term_timeout=1.5,
              change_directory="/tmp", flags=frozenset({"no_pty"}))
    spec = SpawnSpec(**sched.spawn_fields(p, ["A=1"]))
    assert (spec.name, spec.argv, spec.env, spec.cwd) == ("ctl", ["ctl", "--rate", "a b"],
                                                         ["A=1"], "/tmp")
    assert (spec.priority, spec.affinity, spec.max_output_lines) == (5, [1], 77)
    assert (spec.term_signal, spec.term_timeout, spec.use_pty, spec.shell) == (2, 1.5, False,
                                                                               False)


def test_a_new_spawn_field_is_taken_from_the_config_by_name(monkeypatch) -> None:
    # As if wire/daemon.schema's SPAWN and the config's process model both gained a field.
    spec_cls = dataclasses.make_dataclass("SpawnSpec", [("oom_score", int, 0)],
                                          bases=(SpawnSpec,))
    proc_cls = dataclasses.make_dataclass("Process", [("oom_score", int, 0)],
                                          bases=(model.Process,))
    monkeypatch.setattr(sched, "SpawnSpec", spec_cls)
    base = dataclasses.asdict(_proc())
    p = proc_cls(**{f.name: base[f.name] for f in dataclasses.fields(model.Process)},
                 oom_score=-500)
    fields = sched.spawn_fields(p, [])
    assert fields["oom_score"] == -500
    assert spec_cls(**fields).oom_score == -500
