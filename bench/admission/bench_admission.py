"""Benchmark of client admission (issue 33: "manager admission adds <= 1 ms to client
connect"): the time of libln's ln_client_create (connect, HELLO, admission, WELCOME) plus
ln_client_destroy against four managers started in the same run: over loopback without
admission settings (the baseline) and with `client_uids` (peer credentials from
/proc/net/tcp); over this host's non-loopback address without admission settings (the
baseline of remote clients) and with `client_key_file` (the CHALLENGE/AUTH handshake, HMAC
on both sides).  Connects round-robin over the four so drift hits all alike.  Prints a table
and the goal with PASS/MISS, writes bench/results/admission.json and admission.md.
Builds nothing: run scons first.  `--quick` for a short run."""

from __future__ import annotations

import argparse
import ctypes
import json
import os
import platform
import re
import secrets
import socket
import statistics
import subprocess
import sys
import tempfile
import time
import uuid
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(REPO / "python"))  # this checkout's manager and libln

from links_and_nodes import _clientlib as C  # noqa: E402

ROUNDS, QUICK_ROUNDS = 400, 40
GOAL_MS = 1.0  # admission's extra median connect time
READY = re.compile(r"listening on \S+:(\d+)$")
CASES = (("loopback, no admission settings", "loopback", ""),
         ("loopback, client_uids (peer credentials)", "loopback", "client_uids: {uid}"),
         ("remote address, no admission settings", "remote", ""),
         ("remote address, client_key_file (key handshake)", "remote",
          "client_key_file: {key}"))


def remote_address() -> str | None:
    """This host's address on its default route, if it is not loopback."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        try:
            probe.connect(("192.0.2.1", 9))
        except OSError:
            return None
        address = probe.getsockname()[0]
    return None if address.startswith("127.") else address


def start_manager(tmp: Path, index: int, keys: str) -> tuple[subprocess.Popen[bytes], int]:
    instance = f"adm{os.getpid()}x{uuid.uuid4().hex[:6]}"
    config = tmp / f"{instance}.lnc"
    config.write_text(f"instance\nname: {instance}\nmanager: :1\n{keys}\n")
    env = dict(os.environ, LN_RUNTIME_DIR=str(tmp / f"run{index}"),
               PYTHONPATH=str(REPO / "python"))
    proc = subprocess.Popen([sys.executable, "-m", "links_and_nodes.manager", "-c", str(config),
                             "--no-console", "--port", "0", "--host", "0.0.0.0",
                             "--instance", instance, "--log-level", "warning",
                             "--daemon-key-file", str(tmp / "daemon.key")],
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, env=env)
    assert proc.stdout is not None
    line = proc.stdout.readline().decode().strip()
    match = READY.search(line)
    if not match:
        proc.kill()
        raise SystemExit(f"ln_manager did not start: {line!r}")
    return proc, int(match.group(1))


def connect_ms(address: bytes) -> float:
    opts = C.ClientOptions()
    C.ln_client_options_init(ctypes.byref(opts))
    opts.manager = address
    opts.flags |= C.LN_CLIENT_NO_RECONNECT
    handle = ctypes.c_void_p()
    start = time.perf_counter()
    C.ln_client_create(ctypes.byref(handle), b"bench", ctypes.byref(opts))
    C.ln_client_destroy(handle)
    return (time.perf_counter() - start) * 1e3


def measure(rounds: int, remote: str, tmp: Path) -> list[dict[str, Any]]:
    key = tmp / "client.key"
    key.write_text(secrets.token_hex(32) + "\n")
    key.chmod(0o600)
    os.environ["LN_CLIENT_KEY_FILE"] = str(key)
    managers, addresses = [], []
    try:
        for index, (_, where, keys) in enumerate(CASES):
            proc, port = start_manager(tmp, index, keys.format(uid=os.geteuid(), key=key))
            managers.append(proc)
            host = "127.0.0.1" if where == "loopback" else remote
            addresses.append(f"{host}:{port}".encode())
        samples: list[list[float]] = [[] for _ in CASES]
        for address in addresses:  # warm-up: imports, first connections
            for _ in range(5):
                connect_ms(address)
        for _ in range(rounds):
            for index, address in enumerate(addresses):
                samples[index].append(connect_ms(address))
    finally:
        for proc in managers:
            proc.terminate()
            proc.wait(30)
    return [{"case": name, "median_ms": statistics.median(s),
             "p90_ms": statistics.quantiles(s, n=10)[-1], "min_ms": min(s), "samples": len(s)}
            for (name, _, _), s in zip(CASES, samples, strict=True)]


def report(rows: list[dict[str, Any]], quick: bool) -> tuple[str, dict[str, Any]]:
    extra_local = rows[1]["median_ms"] - rows[0]["median_ms"]
    extra_key = rows[3]["median_ms"] - rows[2]["median_ms"]
    worst = max(extra_local, extra_key)
    verdict = "PASS" if worst <= GOAL_MS else "MISS"
    lines = ["| case | median ms | p90 ms | min ms | samples |", "|---|---|---|---|---|"]
    lines += [f"| {r['case']} | {r['median_ms']:.3f} | {r['p90_ms']:.3f} | {r['min_ms']:.3f} "
              f"| {r['samples']} |" for r in rows]
    lines += ["", f"admission adds (median): peer credentials {extra_local:+.3f} ms, key "
                  f"handshake {extra_key:+.3f} ms; goal <= {GOAL_MS} ms: {verdict}"]
    data = {"benchmark": "admission", "quick": quick, "python": platform.python_version(),
            "machine": platform.machine(), "cpus": os.cpu_count(), "rows": rows,
            "extra_ms": {"peer_credentials": extra_local, "key_handshake": extra_key},
            "goal_ms": GOAL_MS, "verdict": verdict}
    return "\n".join(lines), data


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help=f"{QUICK_ROUNDS} rounds, not "
                                                             f"{ROUNDS}")
    parser.add_argument("--out", type=Path, default=REPO / "bench" / "results",
                        help="where admission.json and admission.md go")
    args = parser.parse_args()
    remote = remote_address()
    if remote is None:
        print("bench_admission: this host has no non-loopback address", file=sys.stderr)
        return 1
    with tempfile.TemporaryDirectory(prefix="ln_bench_adm") as tmp:
        rows = measure(QUICK_ROUNDS if args.quick else ROUNDS, remote, Path(tmp))
    table, data = report(rows, args.quick)
    print(table)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "admission.json").write_text(json.dumps(data, indent=2) + "\n")
    (args.out / "admission.md").write_text(
        "# Client admission: connect time (bench/admission/bench_admission.py"
        f"{' --quick' if args.quick else ''})\n\n{table}\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
