"""ln_play's control service (md ln/player): step, seek, pause, resume and set_rate, with
the exact samples each publishes, in order, nothing lost or doubled."""

from __future__ import annotations

from .conftest import Lab
from .player_control import (
    T0,
    Control,
        Played,
    start_player,
    subscribe,
    write_recording,
)
from .recording import WAIT


def test_step_seek_rate_resume_publish_exactly_the_expected_samples(lab: Lab) -> None:
    path = lab.tmp / "ctl.mcap"
    order = write_recording(path, 20, 100_000_000)
    seq = [(topic, i) for _, topic, i in order]
    with lab.client("sink") as clnt:
        played = Played(subscribe(clnt))
        proc, name = start_player(lab, path, "--start-paused", "--wait-for-subscribers")
        ctl = Control(clnt, name)
        st = ctl("status")
        assert (st.status, st.state, st.played, st.position_ns) == (0, "paused", 0, T0)
        assert (st.first_ns, st.last_ns, st.rate) == (T0, order[-1][0], 1.0)
        for k in range(3):
            st = ctl("step")
            assert (st.state, st.played, st.position_ns) == ("paused", k + 1, order[k][0])
        assert played.take(3) == seq[:3]
        assert played.nothing_more()

        st = ctl("seek", time_ns=1_000_000_000, relative=True)  # a10 is next
        assert (st.state, st.played, st.position_ns) == ("paused", 3, T0 + 1_000_000_000)
        assert played.nothing_more()
        ctl("step")
        assert played.take(1) == [("ctl.a", 10)]
        ctl("seek", time_ns=T0 + 1_220_000_000)  # between a12 (1.2 s) and b12 (1.25 s)
        st = ctl("step")
        assert (st.played, st.position_ns) == (5, T0 + 1_250_000_000)
        assert played.take(1) == [("ctl.b", 12)]

        ctl("seek", time_ns=0, relative=True)
        assert ctl("set_rate", rate=4.0).rate == 4.0
        refused = ctl("set_rate", rate=-1.0)
        assert (refused.status, refused.rate) == (-1, 4.0) and "positive" in refused.error
        unknown = ctl("jump")
        assert unknown.status == -1 and "unknown command 'jump'" in unknown.error
        assert played.nothing_more()
        assert ctl("resume").state == "playing"
        assert played.take(len(seq)) == seq
        assert proc.wait(timeout=WAIT) == 0
        assert played.nothing_more()
    assert f"published {5 + len(seq)} samples" in lab.log("play.log")


def test_pause_stands_still_and_resume_loses_and_doubles_nothing(lab: Lab) -> None:
    path = lab.tmp / "ctl.mcap"
    order = write_recording(path, 60, 50_000_000)
    seq = [(topic, i) for _, topic, i in order]
    with lab.client("sink") as clnt:
        played = Played(subscribe(clnt))
        proc, name = start_player(lab, path, "--wait-for-subscribers")
        ctl = Control(clnt, name)
        first = played.take(5)
        paused = ctl("pause")
        p = paused.played
        assert paused.state == "paused" and 5 <= p < len(seq)
        assert order[p - 1][0] <= paused.position_ns <= order[p][0]
        middle = played.take(p - 5)
        assert played.nothing_more()  # nothing is published while paused
        again = ctl("status")
        assert (again.state, again.played, again.position_ns) == ("paused", p,
                                                                  paused.position_ns)
        ctl("set_rate", rate=20.0)
        ctl("resume")
        rest = played.take(len(seq) - p)
        assert proc.wait(timeout=WAIT) == 0
        assert first + middle + rest == seq
        assert played.nothing_more()
