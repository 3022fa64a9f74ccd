"""The annotation page's HTTP API, without a browser."""

from __future__ import annotations

import json
import threading
import urllib.error
import urllib.request

import pytest

from havln_mj.annotator.server import AnnotationServer
from havln_mj.annotator.session import AnnotationSession
from havln_mj.scene.scan import load_scan


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    scan = load_scan("proc-0")
    path = tmp_path_factory.mktemp("annotate") / "placements.json"
    srv = AnnotationServer(AnnotationSession(scan, path, size=(64, 48)), port=0)
    threading.Thread(target=srv.serve_forever, daemon=True).start()
    yield srv
    srv.shutdown()
    srv.server_close()


def _call(server, method, route, body=None, headers=None):
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(server.url.rstrip("/") + route, data=data, method=method)
    if body is not None:
        req.add_header("Content-Type", "application/json")
    for k, v in (headers or {}).items():
        req.add_header(k, v)
    try:
        with urllib.request.urlopen(req, timeout=30) as res:
            return res.status, res.headers["Content-Type"], res.read()
    except urllib.error.HTTPError as err:
        return err.code, err.headers["Content-Type"], err.read()


def test_page_and_scene(server):
    status, kind, body = _call(server, "GET", "/")
    assert status == 200 and kind.startswith("text/html") and b"/static/app.js" in body
    for asset in ("/static/app.js", "/static/style.css"):
        assert _call(server, "GET", asset)[0] == 200
    status, _, body = _call(server, "GET", "/api/scene")
    scene = json.loads(body)
    assert status == 200 and scene["plan"]["scene"] == "proc-0"
    assert {r["code"] for r in scene["catalog"]["regions"]} >= {"k", "h"}
    assert scene["placements"].endswith("placements.json")
    assert _call(server, "GET", "/nothing")[0] == 404


def test_people_save_and_load(server):
    vp = server.session.scan.graph.nodes[0]
    person = {"viewpoint": vp, "activity": "kitchen/dishwasher", "model": 1, "heading_deg": 45}
    status, _, body = _call(server, "PUT", "/api/people", [person])
    assert status == 200 and json.loads(body)[0]["plays"] == "kitchen/dishwasher"
    status, _, body = _call(server, "POST", "/api/save", {})
    saved = json.loads(body)
    assert status == 200 and saved["people"] == 1
    _call(server, "PUT", "/api/people", [])
    status, _, body = _call(server, "POST", "/api/load", {"path": saved["path"]})
    assert status == 200 and [p["viewpoint"] for p in json.loads(body)["people"]] == [vp]


def test_bad_requests_say_why(server):
    status, kind, body = _call(server, "PUT", "/api/people", [{"viewpoint": "nowhere"}])
    assert status == 400 and kind == "application/json" and "activity" in json.loads(body)["error"]
    status, _, body = _call(server, "GET", "/api/view.png?viewpoint=nowhere")
    assert status == 400 and "unknown viewpoint 'nowhere'" in json.loads(body)["error"]
    status, _, body = _call(server, "GET", "/api/view.png")
    assert status == 400 and "missing query parameter 'viewpoint'" in json.loads(body)["error"]
    # Writes must be JSON, from this page: other sites' forms and pages are refused.
    req = urllib.request.Request(server.url + "api/save", data=b"path=/etc/x", method="POST")
    with pytest.raises(urllib.error.HTTPError) as err:
        urllib.request.urlopen(req, timeout=30)
    assert err.value.code == 400
    evil = {"Origin": "http://evil.example"}
    assert _call(server, "POST", "/api/save", {}, evil)[0] == 403
    assert _call(server, "GET", "/api/scene", headers={"Host": "evil.example:80"})[0] == 403
