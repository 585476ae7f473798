"""Protected service calls between hosts across a manager restart (docs/security.md, "Remote
service calls"): the new manager makes a new service key; a caller's TCP connection made
before the restart keeps its keys and goes on, and a new connection after it uses the new
key on both sides."""

from __future__ import annotations

import json

from polling import wait_for

from .conftest import LIMIT, REPO, Restarts

# Calls over TCP (another host id than the provider's): one, then on a line from stdin one
# more on the same connection and one on a new connection, each printed as JSON.
CALLER = """
import json, os, sys
os.environ["LN_HOST_ID"] = "another-host"
import links_and_nodes as ln
ln.add_message_definition_dir(sys.argv[1])
clnt = ln.client("tcp_caller")
def call(svc, text):
    svc.req.goal = [0.5] * 7
    svc.req.max_velocity = 0.5
    svc.req.constraints = [{"data": text}]
    try:
        return svc.call(timeout=60.0).status
    except ln.LnError as exc:
        return str(exc)
old = clnt.get_service("rc.plan", "robot/plan_path")
print(json.dumps([call(old, "before")]), flush=True)
sys.stdin.readline()
new = clnt.get_service("rc.plan", "robot/plan_path")
print(json.dumps([call(old, "same connection"), call(new, "new connection")]), flush=True)
"""


def test_tcp_calls_across_a_manager_restart(restarts: Restarts) -> None:
    restarts.tool("service_tool", "provide", "rc.plan")
    caller = restarts.python(CALLER, str(REPO / "tests" / "fixtures" / "md" / "services"))
    assert caller.stdout is not None and caller.stdin is not None
    assert json.loads(caller.stdout.readline()) == [1]
    restarts.restart()
    wait_for(lambda: "rc.plan" in restarts.services(), "the provider registered again")
    wait_for(lambda: any("tcp_caller" in line and "reconnected" in line
                         for line in restarts.log().splitlines()), "the caller reconnected")
    caller.stdin.write("go\n")
    caller.stdin.flush()
    assert json.loads(caller.stdout.readline()) == [1, 1]
    caller.stdin.close()
    assert caller.wait(timeout=LIMIT) == 0
