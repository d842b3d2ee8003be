"""The studio's foundation: pages, sessions, downloads, the token gate, jobs, uploads, the command."""
from __future__ import annotations

import asyncio
import os
import subprocess
import sys
import time

import pytest

from roughness.core.errors import InputError
from roughness.studio import jobs
from roughness.studio.app import PAGES, StudioSettings
from roughness.studio.sessions import Sessions
from roughness.studio.uploads import MAX_UPLOAD_BYTES, missing_units, open_heightmap, upload_path
from studio_helpers import running_studio

pytestmark = pytest.mark.anyio


async def test_index_links_every_page(studio):
    await studio.user.open("/")
    for name in PAGES:
        page = __import__(name, fromlist=["TITLE"])
        await studio.user.should_see(page.TITLE)
        await studio.user.should_see(page.SUMMARY)


async def test_each_tab_has_its_own_session_and_folder(studio):
    await studio.user.open("/texture")
    other = studio.new_user()
    await other.open("/texture")
    assert len(studio.sessions) == 2
    folders = {s.folder for s in studio.sessions._live.values()}
    assert len(folders) == 2 and all(f.is_dir() for f in folders)
    other.client.delete()  # the tab goes away: its session and folder with it
    await asyncio.sleep(0.1)  # (delete handlers may run as tasks)
    assert len(studio.sessions) == 1 and sum(f.is_dir() for f in folders) == 1


async def test_downloads_only_from_the_session_folder(studio, tmp_path):
    session = studio.sessions.open()
    session.path("report.json").write_text("{}")
    secret = tmp_path / "secret.txt"
    secret.write_text("not yours")
    ok = await studio.http.get(session.download_url("report.json"))
    assert ok.status_code == 200 and ok.text == "{}"
    for bad in (f"/download/{session.id}/..%2F..%2Fsecret.txt", f"/download/{session.id}/.hidden",
                f"/download/{session.id}/{secret}", "/download/not-a-session/report.json",
                f"/download/{session.id}/missing.json"):
        assert (await studio.http.get(bad)).status_code == 404, bad
    with pytest.raises(InputError, match="plain file name"):
        session.path("../x")


def test_sessions_removed_at_end_and_close():
    sessions = Sessions()
    one, two = sessions.open(), sessions.open()
    sessions.end(one)
    assert not one.folder.exists() and two.folder.exists()
    sessions.close()
    assert not two.folder.exists() and not sessions.root.exists()


async def test_token_gate_refuses_requests_without_the_token():
    async with running_studio(StudioSettings(show=False, token="s3cret-token")) as running:
        assert (await running.http.get("/texture")).status_code == 403
        assert (await running.http.get("/texture?token=wrong")).status_code == 403
        given = await running.http.get("/texture?token=s3cret-token")
        assert given.status_code == 200 and "roughness_studio_token" in given.headers["set-cookie"]
        assert (await running.http.get("/texture")).status_code == 200  # the cookie carries it


def _count(report, n: int, pause_s: float) -> int:
    for i in range(n):
        report(i / n, f"step {i + 1} of {n}")
        time.sleep(pause_s)
    return n


def _refuse(report) -> None:
    raise InputError("lambda_mm must be positive", parameter="lambda_mm")


def _wait(job: jobs.Job, timeout_s: float = 60.0) -> jobs.JobState:
    end = time.monotonic() + timeout_s
    while job.poll().status == jobs.RUNNING and time.monotonic() < end:
        time.sleep(0.05)
    return job.state


def test_job_runs_to_its_result_with_progress():
    state = _wait(jobs.Job("count", _count, 3, 0.01))
    assert (state.status, state.result, state.done) == (jobs.DONE, 3, 1.0)


def test_job_error_is_the_cli_message_not_a_traceback():
    state = _wait(jobs.Job("refuse", _refuse))
    assert state.status == jobs.FAILED
    assert state.error == "error: lambda_mm must be positive"


def test_job_errors_name_an_actions_flags():
    flags = jobs.cli_flags("object feel")
    assert flags["printer"] == "--printer" and flags["regions"] == "--region"  # an alias of the action's parser
    assert jobs.cli_flags("object texture")["edge_mm"] == "--edge-mm"


def test_job_cancel_ends_its_process():
    job = jobs.Job("long", _count, 1000, 0.05)
    end = time.monotonic() + 60
    while job.poll().text == "starting" and time.monotonic() < end:
        time.sleep(0.05)
    assert job.state.text.startswith("step ")
    job.cancel()
    assert job.state.status == jobs.CANCELLED and not job._process.is_alive()


def test_upload_limit_and_stored_name(tmp_path):
    session = Sessions().open()
    path = upload_path(session, "../../etc/passwd", 3)
    assert path.parent == session.folder and path.name == "passwd"
    assert upload_path(session, "big.png", MAX_UPLOAD_BYTES).name == "big.png"
    with pytest.raises(InputError, match="upload limit"):
        upload_path(session, "big.png", MAX_UPLOAD_BYTES + 1)


def test_upload_read_as_the_cli_reads_it(tmp_path):
    from roughness.studio.texture_source import example_path

    with pytest.raises(InputError) as err:
        open_heightmap(example_path())
    assert missing_units(err.value) == ("pixel_mm", "height_mm")
    cli = subprocess.run([sys.executable, "-m", "roughness.cli", "predict", str(example_path())],
                         capture_output=True, text=True)
    assert cli.returncode == 2 and cli.stderr.strip() == f"roughness: error: {err.value}"
    with pytest.raises(InputError) as err:
        open_heightmap(example_path(), pixel_mm=0.05)
    assert missing_units(err.value) == ("height_mm",)
    assert open_heightmap(example_path(), 0.05, 1.0).heightmap.pixel_mm == 0.05


def test_command_without_the_extra_exits_2_with_the_extra_named(tmp_path):
    blocker = tmp_path / "nicegui"
    blocker.mkdir()
    (blocker / "__init__.py").write_text("raise ModuleNotFoundError('No module named nicegui', name='nicegui')\n")
    run = subprocess.run([sys.executable, "-m", "roughness.cli", "studio", "--no-browser"], capture_output=True,
                         text=True, env={"PYTHONPATH": str(tmp_path), "PATH": "/usr/bin:/bin"})
    assert run.returncode == 2
    assert "'studio' extra" in run.stderr and "Traceback" not in run.stderr


def test_command_on_another_host_warns_and_needs_its_token():
    import re
    import urllib.error
    import urllib.request

    from studio_helpers import free_port

    port = free_port()
    env = {k: v for k, v in os.environ.items() if k != "PYTEST_CURRENT_TEST"}
    server = subprocess.Popen([sys.executable, "-m", "roughness.cli", "studio", "--host", "127.0.0.2", "--port",
                               str(port), "--no-browser"], stderr=subprocess.PIPE, text=True, env=env)
    try:
        line = server.stderr.readline()
        assert "warning: serving on 127.0.0.2" in line
        token = re.search(r"\?token=(\S+)", line).group(1)
        base = f"http://127.0.0.2:{port}/texture"
        for _ in range(100):
            try:
                urllib.request.urlopen(base, timeout=1)
            except urllib.error.HTTPError as refused:
                assert refused.code == 403
                break
            except OSError:
                time.sleep(0.2)
        else:
            raise AssertionError("the server never answered")
        assert urllib.request.urlopen(f"{base}?token={token}", timeout=5).status == 200
    finally:
        server.terminate()
        server.wait(timeout=10)
