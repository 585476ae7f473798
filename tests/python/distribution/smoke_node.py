"""The Python process of the installed-package smoke test (install_smoke.py): subscribes
smoke.state (the C publisher), republishes every sample it reads on smoke.echo and serves
smoke.set_gains, answering how many samples it has seen.  Runs until it is stopped."""

import links_and_nodes as ln


class Gains(ln.service_provider):
    def __init__(self, clnt: ln.client) -> None:
        ln.service_provider.__init__(self, clnt, "smoke")
        self.seen = 0
        self.wrap_service_provider("set_gains", "robot/set_gains")

    def set_gains(self, kp: object, kd: object, profile_name: str) -> dict[str, object]:
        return {"ok": 1, "message": f"{profile_name}: {self.seen} samples seen"}


clnt = ln.client("smoke_node")
sub = clnt.subscribe("smoke.state", "robot/joint_state")
pub = clnt.publish("smoke.echo", "robot/joint_state")
gains = Gains(clnt)
clnt.handle_service_group_in_thread_pool(None, "main")
print("smoke_node: subscribed, publishing, serving", flush=True)
while True:
    packet = sub.read(timeout=1.0)
    if packet is not None:
        gains.seen += 1
        pub.write(packet)
