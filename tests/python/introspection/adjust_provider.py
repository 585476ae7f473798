"""The service provider of the introspection tests, a process of its own:

    adjust_provider.py ADDRESS SERVICE MD_DIR

provides SERVICE with md lntest/adjust (from MD_DIR) and answers as `adjust(request)` says
(a request named "fail" gets an error response); prints "ready" once registered.  Runs
until killed."""

from __future__ import annotations

import sys
from typing import Any

import links_and_nodes as ln


def adjust(req: dict[str, Any]) -> dict[str, Any]:
    """The response to a request of lntest/adjust (given as plain values)."""
    tags = [t["data"] for t in req["tags"]]
    target = req["target"]
    return {"total": sum(req["values"]) + req["offset"],
            "text": f"{req['name']}: {','.join(tags)}",
            "target": {"position": [2 * p for p in target["position"]],
                       "orientation": target["orientation"]},
            "count": len(tags)}


def main() -> None:
    address, name, md_dir = sys.argv[1:4]
    ln.add_message_definition_dir(md_dir)
    clnt = ln.client("adjuster", address)

    def handler(request: ln.service_request) -> None:
        req = request.req.to_dict()
        if req.get("name") == "fail":
            request.respond_error("asked to fail")
        elif "tags" not in req:  # the other directory's lntest/adjust
            request.respond({"total": sum(req["values"])})
        else:
            request.respond(adjust(req))

    clnt.get_service_provider(name, "lntest/adjust", handler)
    print("ready", flush=True)
    while True:
        clnt.wait_and_handle_service_group_requests(None, 1.0)


if __name__ == "__main__":
    main()
