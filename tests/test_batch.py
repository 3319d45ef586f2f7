"""``meshrepair batch`` on a real Dask LocalCluster (2 worker processes) and on a separately
started ``dask scheduler`` + ``dask worker``: good meshes equal the single command's result, bad
ones are recorded with their message, resume skips what is done, a killed worker loses nothing.
"""

import json
import os
import signal
import subprocess
import sys
import time
from importlib.resources import files
from pathlib import Path

import numpy as np
import pytest
import trimesh

pytest.importorskip("distributed")  # a core dependency: this only guards a broken install

from distributed.diagnostics.plugin import WorkerPlugin  # noqa: E402

import meshrepair.batch.orchestrate as batch
from meshrepair.batch.collection import collect_inputs  # noqa: E402
from meshrepair.batch.jobs import run_job  # noqa: E402
from meshrepair.cli import main  # noqa: E402
from meshrepair.errors import MeshRepairError  # noqa: E402
from meshrepair.io import read_mesh, write_mesh  # noqa: E402
from meshrepair.model.noise import add_noise  # noqa: E402

DATA = files("meshrepair") / "data"
GOOD = ("a.ply", "sub/b.ply", "sub/deeper/c.obj")
BAD = {"broken.ply": "truncated file", "notamesh.off": "cannot read",
       "raises.ply": "non-manifold edges"}


def _noisy_sphere(level: int, seed: int):
    s = trimesh.creation.icosphere(level)
    V = np.asarray(s.vertices, float)
    F = np.asarray(s.faces, np.int64)
    return add_noise(V, F, 0.3, seed=seed), F


def make_collection(root: Path) -> Path:
    """a.ply (noisy fandisk), sub/b.ply, sub/deeper/c.obj (noisy spheres), broken.ply
    (truncated), notamesh.off (text), raises.ply (non-manifold: denoise refuses), readme.txt."""
    root.mkdir(parents=True)
    (root / "sub" / "deeper").mkdir(parents=True)
    (root / "a.ply").write_bytes((DATA / "fandisk_noisy.ply").read_bytes())
    write_mesh(root / "sub" / "b.ply", *_noisy_sphere(3, 1))
    write_mesh(root / "sub" / "deeper" / "c.obj", *_noisy_sphere(2, 2))
    (root / "broken.ply").write_bytes((DATA / "fandisk.ply").read_bytes()[:400])
    (root / "notamesh.off").write_text("this is a text file, not a mesh\n")
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]], float)
    write_mesh(root / "raises.ply", V, np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]]))
    (root / "readme.txt").write_text("not a mesh, not matched by the default pattern\n")
    return root


def single_command(task: str, inp: Path, out: Path, *opts: str) -> bytes:
    """The single command's output file, as bytes."""
    assert main([task, str(inp), str(out), "-q", *opts]) == 0
    return out.read_bytes()


@pytest.fixture(scope="module")
def client():
    numba_env = os.environ.get("NUMBA_NUM_THREADS")
    with batch.connect(workers=2, retries=2) as c:
        c.wait_for_workers(2, timeout=120)
        # the workers' thread settings do not leak into this process (numba would refuse a
        # changed NUMBA_NUM_THREADS here once its threads run)
        assert os.environ.get("NUMBA_NUM_THREADS") == numba_env
        yield c


@pytest.fixture(scope="module")
def collection(tmp_path_factory):
    root = make_collection(tmp_path_factory.mktemp("batch") / "in")
    ref = tmp_path_factory.mktemp("single")
    refs = {}
    for rel in GOOD:
        refs[rel] = single_command("denoise", root / rel, ref / Path(rel).name)
    return root, refs


def by_rel(records):
    return {r["rel"]: r for r in records}


def test_denoise_folder_then_resume(client, collection, tmp_path):
    root, refs = collection
    before = {p: p.read_bytes() for p in root.rglob("*") if p.is_file()}
    out = tmp_path / "out"
    events = []
    recs = by_rel(batch.run(root, out, task="denoise", client=client, callback=events.append))
    assert sorted(recs) == sorted([*GOOD, *BAD])  # readme.txt is not a mesh file: not picked
    for rel in GOOD:
        r = recs[rel]
        assert r["status"] == "done", r["error"]
        assert (out / rel).read_bytes() == refs[rel]  # equal to the single command's file
        assert r["vertices"] == len(read_mesh(root / rel).V) and r["seconds"] > 0
        assert r["peak_rss_mb"] > 50 and r["metrics"]["noise_estimate"] > 0
        assert r["threads"] == {"blas": 1, "numba": 1}  # set before the numeric imports
        assert all(Path(r["thumbnails"][k]).is_file() for k in ("before", "after"))
    for rel, msg in BAD.items():
        assert recs[rel]["status"] == "failed" and msg in recs[rel]["error"], recs[rel]
        assert not (out / rel).exists()
    assert {r["worker"] for r in recs.values()} <= set(client.nthreads())
    assert events[0]["event"] == "start" and events[0]["dashboard"].startswith("http")
    assert [e["done"] + e["failed"] for e in events[1:]] == list(range(1, 7))
    # records appended as they finished; report lists failures first
    lines = (out / "batch.jsonl").read_text().splitlines()
    assert sorted(json.loads(s)["rel"] for s in lines) == sorted(recs)
    page = (out / "index.html").read_text()
    assert max(page.index(f">{r}<") for r in BAD) < min(page.index(f">{r}</a>") for r in GOOD)
    assert "non-manifold edges" in page
    # self-contained: the thumbnails are embedded (the PNG bytes the workers wrote), not linked
    import base64

    png = Path(recs["a.ply"]["thumbnails"]["before"]).read_bytes()
    assert f'src="data:image/png;base64,{base64.b64encode(png).decode()}"' in page
    assert "thumbnails/" not in page
    # inputs untouched, no temporary files anywhere
    assert {p: p.read_bytes() for p in root.rglob("*") if p.is_file()} == before
    assert not list(out.rglob("*.tmp"))

    # an existing output is never overwritten silently
    with pytest.raises(MeshRepairError, match="exist already.*--resume.*--force"):
        batch.run(root, out, task="denoise", client=client)
    # resume: the good meshes are skipped, the failed ones retried (and fail again)
    stamp = {rel: (out / rel).stat().st_mtime_ns for rel in GOOD}
    again = by_rel(batch.run(root, out, task="denoise", client=client, resume=True))
    assert all(again[rel].get("resumed") for rel in GOOD)
    assert not any(again[rel].get("resumed") for rel in BAD)
    assert {rel: (out / rel).stat().st_mtime_ns for rel in GOOD} == stamp
    new = [json.loads(s)["rel"] for s in (out / "batch.jsonl").read_text().splitlines()[6:]]
    assert sorted(new) == sorted(BAD)
    assert "(3 resumed)" in (out / "index.html").read_text()
    # other options (or another task) do not match the records: refused without --force
    with pytest.raises(MeshRepairError, match="exist without a record.*add --force"):
        batch.run(root, out, task="denoise", client=client, resume=True, th=40.0)
    # a changed input is not skipped either
    os.utime(root / "a.ply", ns=(time.time_ns(), time.time_ns()))
    third = by_rel(batch.run(root, out, task="denoise", client=client, resume=True,
                             force=True, pattern="a.ply"))
    assert list(third) == ["a.ply"] and not third["a.ply"].get("resumed")
    assert (out / "a.ply").read_bytes() == refs["a.ply"]


def test_worker_killed_mid_batch_loses_nothing(client, collection, tmp_path):
    root, refs = collection
    src = tmp_path / "many"
    src.mkdir()
    names = [f"m{i}.ply" for i in range(8)]
    for n in names:
        (src / n).write_bytes((root / "a.ply").read_bytes())
    out = tmp_path / "out"
    killed = []

    def kill_a_busy_worker(ev):
        if ev["event"] != "mesh" or killed:
            return
        busy = [(w, keys) for w, keys in client.processing().items() if keys]
        assert busy, "no worker busy when the first mesh finished"
        w, keys = busy[0]
        pid = client.run(os.getpid, workers=[w])[w]
        os.kill(pid, signal.SIGKILL)
        killed.append((pid, set(map(str, keys))))

    recs = by_rel(batch.run(src, out, task="denoise", client=client,
                            callback=kill_a_busy_worker))
    assert killed
    pid, keys = killed[0]
    assert sorted(recs) == names
    for n in names:
        assert recs[n]["status"] == "done", recs[n]["error"]
        assert (out / n).read_bytes() == refs["a.ply"]
    # the meshes the killed worker held were re-run by another worker process
    rerun = [r for r in recs.values() if r["key"] in keys]
    assert len(rerun) == len(keys) and all(r["pid"] != pid for r in rerun)
    assert not list(out.rglob(".*.tmp"))  # no partial output left behind
    client.wait_for_workers(2, timeout=120)  # the nanny replaced the killed worker
    assert pid not in client.run(os.getpid).values()


class CrashOnName(WorkerPlugin):
    """Make a worker process die (like a segfault or the OOM killer) on files named crash*."""

    name = "test-crash-on-name"

    def setup(self, worker):
        import meshrepair.io as io

        if getattr(io.read_mesh, "_crash", False):
            return
        orig = io.read_mesh

        def read_mesh(path):
            if Path(path).name.startswith("crash"):
                os._exit(17)
            return orig(path)

        read_mesh._crash = True
        io.read_mesh = read_mesh


def test_worker_dying_every_time_is_recorded_as_failed(collection, tmp_path):
    import cloudpickle

    root, refs = collection
    src = tmp_path / "in"
    src.mkdir()
    (src / "crash.ply").write_bytes((root / "a.ply").read_bytes())
    (src / "fine.ply").write_bytes((root / "a.ply").read_bytes())
    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    try:  # its own cluster: 2 workers, a mesh is re-run once after its worker died
        with batch.connect(workers=2, retries=1) as c:
            c.register_plugin(CrashOnName())
            recs = by_rel(batch.run(src, tmp_path / "out", task="denoise", client=c))
    finally:
        cloudpickle.unregister_pickle_by_value(sys.modules[__name__])
    assert recs["fine.ply"]["status"] == "done"
    assert (tmp_path / "out" / "fine.ply").read_bytes() == refs["a.ply"]
    bad = recs["crash.ply"]
    assert bad["status"] == "failed" and bad["error_type"] == "KilledWorker"
    assert "died on every attempt" in bad["error"]
    assert not (tmp_path / "out" / "crash.ply").exists()


def test_cli_batch_fill_and_option_checks(client, tmp_path, capsys):
    src = tmp_path / "in"
    src.mkdir()
    s = trimesh.creation.icosphere(3)
    V, F = np.asarray(s.vertices, float), np.asarray(s.faces, np.int64)
    keep = ~(V[F].mean(axis=1)[:, 2] > 0.8)  # cut a cap: one hole
    write_mesh(src / "holed.ply", V, F[keep])
    ref = single_command("fill", src / "holed.ply", tmp_path / "ref.ply", "--max-hole-size",
                         "200")
    out = tmp_path / "out"
    addr = client.scheduler.address
    rc = main(["batch", str(src), str(out), "--task", "fill", "--max-hole-size", "200",
               "--scheduler", addr, "-q"])
    assert rc == 0
    assert (out / "holed.ply").read_bytes() == ref
    rec = json.loads((out / "batch.jsonl").read_text().splitlines()[-1])
    assert rec["metrics"]["holes_filled"] == 1 and rec["metrics"]["holes_skipped"] == 0
    text = capsys.readouterr().out
    assert "Dask dashboard: http" in text and "1 of 1 meshes repaired" in text
    # options of another task, missing required ones: refused before any work
    assert main(["batch", str(src), str(tmp_path / "o2"), "--task", "denoise",
                 "--keep-border"]) == 2
    assert main(["batch", str(src), str(tmp_path / "o2"), "--task", "inpaint"]) == 2
    assert main(["batch", str(src), str(tmp_path / "o2"), "--task", "complete",
                 "--hole", "0"]) == 2
    assert main(["batch", str(src), str(src), "--task", "denoise"]) == 2
    afile = tmp_path / "afile"
    afile.write_text("x")
    assert main(["batch", str(src), str(afile), "--task", "denoise"]) == 2
    err = capsys.readouterr().err
    assert "exists and is not a folder" in err and afile.read_text() == "x"
    assert "--keep-border not an option of --task denoise" in err
    assert "needs exactly one of --region, --sphere, --box" in err
    assert "needs --template" in err and "is the input folder" in err
    assert not (tmp_path / "o2").exists()
    # bad values of the task's own options: refused before a worker starts, nothing written
    for opts, msg in ((["--task", "denoise", "--lam", "-1"], "lam must be"),
                      (["--task", "denoise", "--th", "999"], "th must be"),
                      (["--task", "fill", "--max-hole-size", "2"], "max_hole_size must be")):
        assert main(["batch", str(src), str(tmp_path / "o3"), *opts, "-q"]) == 2
        assert msg in capsys.readouterr().err
        assert not (tmp_path / "o3").exists()


def test_check_options_checks_the_values():
    from meshrepair.batch.jobs import check_options

    assert check_options("denoise", {"lam": 0.2}) == {"lam": 0.2}
    for task, opts, msg in (("denoise", {"feature_iters": -1}, "feature_iters"),
                            ("fill", {"refine": "no"}, "refine must be True or False"),
                            ("inpaint", {"inner_solver": "x"}, "inner_solver"),
                            ("fill", {"keep_border": 1}, "keep_border")):
        with pytest.raises(MeshRepairError, match=msg):
            check_options(task, opts)


def test_jobs_equal_single_inpaint_and_complete(tmp_path):
    """The per-mesh job (no Dask) writes the single command's file for inpaint and complete."""
    s = trimesh.creation.icosphere(3)
    V, F = np.asarray(s.vertices, float), np.asarray(s.faces, np.int64)
    write_mesh(tmp_path / "ball.ply", V, F)
    ref = single_command("inpaint", tmp_path / "ball.ply", tmp_path / "ref_i.ply",
                         "--sphere", "0,0,1,0.3")
    rec = run_job("inpaint", str(tmp_path / "ball.ply"), str(tmp_path / "job_i.ply"),
                  {"region": ["sphere", [0, 0, 1], 0.3], "attribute": None, "denoise": False,
                   "initial": "bilaplacian", "refine": True})
    assert rec["status"] == "done", rec["error"]
    assert (tmp_path / "job_i.ply").read_bytes() == ref and rec["metrics"]["holes_filled"] == 1
    cap = V[F].mean(axis=1)[:, 2] > 0.8
    write_mesh(tmp_path / "holed.ply", V, F[~cap])
    used = np.unique(F[cap])
    remap = np.full(len(V), -1)
    remap[used] = np.arange(len(used))
    write_mesh(tmp_path / "cap.ply", V[used], remap[F[cap]])
    assert main(["complete", str(tmp_path / "holed.ply"), str(tmp_path / "cap.ply"),
                 str(tmp_path / "ref_c.ply"), "--hole", "0", "--mode", "smooth"]) == 0
    from argparse import Namespace

    from meshrepair.commands.complete import complete_options

    opts = complete_options(Namespace(
        region=None, hole=0, template_region=None, transform=None, strip_rings=2,
        mode="smooth", allow_scale=False, orientation="template", icp="auto", iterations=80,
        th=30.0, denoise=False, mirror=False, max_symmetry_residual=0.1))
    rec = run_job("complete", str(tmp_path / "holed.ply"),
                  str(tmp_path / "job_c.ply"), {"template": "{parent}/cap.ply", **opts})
    assert rec["status"] == "done", rec["error"]
    assert (tmp_path / "job_c.ply").read_bytes() == (tmp_path / "ref_c.ply").read_bytes()
    assert rec["metrics"]["seam_vertices"] > 0
    # a job never writes over its input, whatever the options
    ball = (tmp_path / "ball.ply").read_bytes()
    rec = run_job("denoise", str(tmp_path / "ball.ply"), str(tmp_path / "ball.ply"), {})
    assert rec["status"] == "failed" and "refusing to overwrite the input" in rec["error"]
    assert (tmp_path / "ball.ply").read_bytes() == ball


def test_collect_inputs_folder_glob_list(tmp_path):
    root = make_collection(tmp_path / "in")
    rels = [rel for _, rel in collect_inputs(root)]
    assert rels == sorted([*GOOD, *BAD])
    assert [r for _, r in collect_inputs(root, pattern="*.obj")] == ["sub/deeper/c.obj"]
    assert [r for _, r in collect_inputs(str(root / "**" / "*.ply"))] == [
        "a.ply", "broken.ply", "raises.ply", "sub/b.ply"]
    lst = tmp_path / "list.txt"
    lst.write_text("# meshes\nin/sub/b.ply\n\n" + str(root / "sub/deeper/c.obj") + "\n")
    assert [r for _, r in collect_inputs(lst)] == ["b.ply", "deeper/c.obj"]
    # the batch's own output folder inside the input folder is not an input
    (root / "out").mkdir()
    (root / "out" / "a.ply").write_bytes(b"x")
    assert "out/a.ply" not in [r for _, r in collect_inputs(root, exclude=root / "out")]
    with pytest.raises(MeshRepairError, match="no mesh files"):
        collect_inputs(root, pattern="*.xyz")
    with pytest.raises(MeshRepairError, match="matches no file"):
        collect_inputs(str(root / "*.xyz"))
    with pytest.raises(MeshRepairError, match="neither a folder"):
        collect_inputs(tmp_path / "missing")
    with pytest.raises(MeshRepairError, match="has no option 'keep_border'"):
        batch.run(root, tmp_path / "o", task="denoise", keep_border=True)
    assert not (tmp_path / "o").exists()


def test_scheduler_option_with_separate_dask_processes(collection, tmp_path):
    root, refs = collection
    sched_file = tmp_path / "scheduler.json"
    env = {k: v for k, v in os.environ.items()
           if k not in ("NUMBA_NUM_THREADS", "VECLIB_MAXIMUM_THREADS", "NUMEXPR_NUM_THREADS")}
    py = sys.executable
    procs = []
    try:
        procs.append(subprocess.Popen(
            [py, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", "0",
             "--dashboard-address", "127.0.0.1:0", "--scheduler-file", str(sched_file)],
            env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        deadline = time.time() + 90
        while not sched_file.exists() and time.time() < deadline:
            time.sleep(0.2)
        address = json.loads(sched_file.read_text())["address"]
        procs.append(subprocess.Popen(
            [py, "-m", "distributed.cli.dask_worker", "--scheduler-file", str(sched_file),
             "--nworkers", "2", "--nthreads", "1", "--host", "127.0.0.1", "--no-dashboard"],
            env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        from distributed import Client

        with Client(address, timeout="60s") as c:
            c.wait_for_workers(2, timeout=120)
        out = tmp_path / "out"
        rc = main(["batch", str(root), str(out), "--task", "denoise", "--scheduler", address,
                   "-q"])
        assert rc == 1  # the three bad meshes failed
        recs = {json.loads(s)["rel"]: json.loads(s)
                for s in (out / "batch.jsonl").read_text().splitlines()}
        assert sorted(recs) == sorted([*GOOD, *BAD])
        for rel in GOOD:
            assert recs[rel]["status"] == "done" and (out / rel).read_bytes() == refs[rel]
            assert recs[rel]["threads"] == {"blas": 1, "numba": 1}
        for rel, msg in BAD.items():
            assert msg in recs[rel]["error"]
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in reversed(procs):
            try:
                p.wait(timeout=30)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()


def test_records_survive_an_interrupted_write_and_resume_rules(tmp_path):
    from meshrepair.batch.collection import RecordWriter, is_done, read_records

    w = RecordWriter(tmp_path)
    w.write({"rel": "a.ply", "status": "failed"})
    w.write({"rel": "a.ply", "status": "done", "task": "denoise", "options": {"th": 30.0},
             "version": "0.1.0"})
    w.close()
    with open(tmp_path / "batch.jsonl", "a") as fh:
        fh.write('{"rel": "b.ply", "status": "do')  # the client died mid-line
    recs = read_records(tmp_path)
    assert list(recs) == ["a.ply"] and recs["a.ply"]["status"] == "done"  # latest line wins
    inp, out = tmp_path / "in.ply", tmp_path / "out.ply"
    inp.write_bytes(b"mesh")
    st = inp.stat()
    rec = {**recs["a.ply"], "input_size": st.st_size, "input_mtime_ns": st.st_mtime_ns}
    same = dict(task="denoise", options={"th": 30.0}, version="0.1.0", input=inp, output=out)
    assert not is_done(rec, **same)  # no output file
    out.write_bytes(b"result")
    assert is_done(rec, **same)
    assert not is_done(rec, **{**same, "options": {"th": 40.0}})
    assert not is_done(rec, **{**same, "task": "fill"})
    assert not is_done(rec, **{**same, "version": "0.2.0"})
    inp.write_bytes(b"changed mesh")
    assert not is_done(rec, **same)


def test_index_links_are_encoded_urls(tmp_path):
    """Links of the batch page are URLs: '#', '%', spaces and ':' of file names are
    percent-encoded ('part #2/scan#1.ply' linked to a fragment of 'part ')."""
    from meshrepair.batch.report import _rel_link

    out = tmp_path / "out"
    assert _rel_link(str(out / "part #2" / "scan#1.ply"), out) == "part%20%232/scan%231.ply"
    assert _rel_link(str(out / "100%.ply"), out) == "100%25.ply"
    assert _rel_link(str(out / "a:b.ply"), out) == "a%3Ab.ply"  # not a URL scheme
    assert _rel_link(None, out) is None
