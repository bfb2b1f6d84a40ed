"""The batch's named steps, each on its own: the shared option checks, the specs (checked once),
the engine's options, the plan against a previous status table, the recorder, the command's
summary; and the progress callback naming the steps of a whole run."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from conftest import data_path

from partscale import _options
from partscale.batch import api, job, read_status, run
from partscale.batch.status import StatusTable
from partscale.errors import InputError

# -- the shared option vocabulary ------------------------------------------------------------


def test_res_bounds_and_text_are_checked_before_any_arithmetic():
    assert _options.check_res(16, "res") == 16
    assert _options.check_res(16384.0, "res") == 16384
    assert _options.check_res(" 64 ", "res", text=True) == 64
    for bad, said in [(15, "got 15"), (16385, "got 16385"), (True, "integer res"), (6.5, "6.5")]:
        with pytest.raises(InputError, match=said):
            _options.check_res(bad, "res")
    with pytest.raises(InputError, match="integer res"):
        _options.check_res("64", "res")  # text only where text is read
    with pytest.raises(InputError, match="'many'"):
        _options.check_res("many", "m.csv:3: res", text=True)


def test_ingest_and_the_options_module_share_one_check_res():
    import partscale.ingest

    assert partscale.ingest.check_res is _options.check_res


def test_yes_no_counts_seconds_memory_and_choices():
    assert _options.yes_no(" YES", "square", text=True) is True
    assert _options.yes_no("off", "square", text=True) is False
    with pytest.raises(InputError, match="expected true or false, got 'yes'"):
        _options.yes_no("yes", "square")  # a word is no bool where values are typed
    assert _options.count(0, "retries", lo=0) == 0
    for bad in (True, 1.0, 0, "2"):
        with pytest.raises(InputError, match="workers: expected an integer >= 1"):
            _options.count(bad, "workers")
    assert _options.seconds(1e7, "timeout") == 1e7
    for bad in (0, -1, 1e7 + 1, float("nan"), "a"):
        with pytest.raises(InputError, match="timeout"):
            _options.seconds(bad, "timeout")
    assert _options.memory_size("1.5G") == 3 * 2**29
    assert _options.memory_size("4KiB") == 4096
    for bad in ("0", "-1G", "inf", "1e308", "1025T", True):
        with pytest.raises(InputError, match="memory"):
            _options.memory_size(bad)
    assert _options.choice("ISO ", "render", ("iso", "top")) == "iso"
    assert _options.choices(["glb", ".GLB", " png"], "export", ("glb", "png")) == ["glb", "png"]
    assert _options.choices(" None ", "export", ("glb",)) == []
    with pytest.raises(InputError, match="expected formats among glb, got 'stl'"):
        _options.choices("glb,stl", "export", ("glb",), noun="formats")


# -- specs: the batch's options checked once, a row's own laid over them ---------------------


def test_batch_spec_defaults_and_canonical_values(tmp_path):
    spec = job.batch_spec({})
    assert (spec["res"], spec["export"], spec["segment"], spec["render"]) == (
        128,
        ["csdf"],
        None,
        None,
    )
    spec = job.batch_spec(
        {"res": "48", "square": "yes", "segment": True, "export": "GLB,png", "render": "true"}
    )
    assert spec["res"] == 48 and spec["square"] is True
    assert spec["segment"] == "fast" and spec["render"] == "iso"
    assert spec["export"] == ["glb", "png"]
    assert job.options_hash(spec) == job.options_hash(json.loads(json.dumps(spec)))


def test_a_row_reads_only_its_own_options_the_batch_recipe_is_read_once(tmp_path):
    recipe = tmp_path / "recipe.json"
    edits = {"version": 1, "edits": [{"axis": "x", "zone": ["40%", "60%"], "to": "110%"}]}
    recipe.write_text(json.dumps(edits))
    base = job.batch_spec({"recipe": str(recipe), "export": "glb"})
    assert base["recipe"]["edits"][0]["axis"] == "x"  # the recipe's content, not its path
    recipe.unlink()  # read once: the objects' specs do not read it again
    spec = job.object_spec(base, {"res": "32"}, where="m.csv:2")
    assert spec["res"] == 32 and spec["recipe"] == base["recipe"]
    assert base["res"] == 128  # the batch's spec is left as it was
    # a row switches the batch's recipe off and asks for a size instead
    spec = job.object_spec(base, {"recipe": "none", "fit": "1 = 120%"}, where="m.csv:3")
    assert spec["recipe"] is None and spec["fit"] == ["1", "=", "120%"]
    with pytest.raises(
        InputError, match=r"m\.csv:4: expected a recipe or a size \(fit\), got both"
    ):
        job.object_spec(base, {"fit": "1 = 120%"}, where="m.csv:4")
    with pytest.raises(InputError, match=r"m\.csv:5: expected at least one output"):
        job.object_spec(base, {"export": "none"}, where="m.csv:5")
    with pytest.raises(InputError, match=r"m\.csv:6: res: expected res in"):
        job.object_spec(base, {"res": "16385"}, where="m.csv:6")
    with pytest.raises(InputError, match=r"m\.csv:7: render: expected one of"):
        job.object_spec(base, {"render": "back"}, where="m.csv:7")


# -- the engine's options --------------------------------------------------------------------


def test_check_engine_refuses_bad_values_and_sizes_the_workers():
    eng = api.check_engine("local", 2, None, None, None, 1)
    assert eng.processes == 2 and eng.threads >= 1 and eng.memory > 0
    assert api.check_engine("local", None, 5, "1M", None, 0).memory == 2**20
    for args, said in [
        (("spark", None, None, None, None, 1), "engine: expected one of local, ray"),
        (("local", True, None, None, None, 1), "workers: expected an integer >= 1"),
        (("local", 0, None, None, None, 1), "workers"),
        (("local", 1, 0, None, None, 1), "timeout"),
        (("local", 1, None, "lots", None, 1), "memory"),
        (("local", 1, None, None, None, -1), "retries: expected an integer >= 0"),
        (("local", 1, None, None, "auto", 1), "address: expected only with engine ray"),
    ]:
        with pytest.raises(InputError, match=said):
            api.check_engine(*args)


def test_check_outdir_refuses_a_file(tmp_path):
    (tmp_path / "f").write_text("")
    with pytest.raises(InputError, match="expected an output folder, got a file"):
        api.check_outdir(tmp_path / "f")
    assert api.check_outdir(tmp_path / "new") == tmp_path / "new"


# -- the plan against a previous table, the recorder ------------------------------------------


def _objects(tmp_path: Path):
    table = data_path("kenney/table.glb")
    spec = job.batch_spec({"res": 32, "export": "glb"})
    return api.read_inputs([table], tmp_path / "out", spec)


def test_plan_skips_done_leaves_failed_and_reruns_the_rest(tmp_path):
    objects = _objects(tmp_path)
    (item, spec) = objects[0]
    out = tmp_path / "out"
    (out / "table").mkdir(parents=True)
    first = api.plan(objects, out, {})
    assert [t["name"] for t in first.tasks] == ["table"] and first.tasks[0]["attempts"] == 1
    task = first.tasks[0]
    done = {
        "state": "done",
        "input_hash": task["input_hash"],
        "options_hash": task["options_hash"],
        "outputs": "table/table.glb",
        "attempts": "1",
        "error": "",
    }
    # done, but its output gone: run again, the attempts counted on
    again = api.plan(objects, out, {"table": done})
    assert again.tasks and again.tasks[0]["attempts"] == 2
    (out / "table" / "table.glb").write_bytes(b"glTF")
    assert api.plan(objects, out, {"table": done}).skipped == ["table"]
    # other options: run again
    changed = [(item, {**spec, "res": 48})]
    assert api.plan(changed, out, {"table": done}).tasks
    failed = {**done, "state": "failed", "error": "boom"}
    assert api.plan(objects, out, {"table": failed}).not_retried == [("table", "boom")]
    assert api.plan(objects, out, {"table": failed}, retry_failed=True).tasks


def test_recorder_writes_rows_result_and_names_the_step(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    table = StatusTable(out)
    result = api.BatchResult(outdir=out, status=table.path)
    said: list[tuple[float, str]] = []
    rec = api.Recorder(table, result, lambda f, m: said.append((f, m)), total=2)
    tasks = api.plan(_objects(tmp_path), out, {}).tasks
    task = tasks[0]
    rec.on_start(task)
    assert read_status(table.path)["table"]["state"] == "running"
    rec.on_finish(
        task,
        {"ok": False, "error": "bad mesh", "outputs": [], "seconds": 1.25, "peak_memory": 2**20},
    )
    row = read_status(table.path)["table"]
    assert (row["state"], row["error"], row["seconds"], row["peak_memory_mib"]) == (
        "failed",
        "bad mesh",
        "1.250",
        "1.0",
    )
    assert result.failed == [("table", "bad mesh")] and result.peak_memory == 2**20
    assert said == [(0.5, "objects: failed table")]
    rec.on_start(task)
    rec.interrupted()
    assert result.interrupted == ["table"]
    assert read_status(table.path)["table"]["state"] == "interrupted"


def test_a_run_reports_its_steps_by_name(tmp_path):
    """A batch whose objects are all done already: the steps, no object run."""
    objects = _objects(tmp_path)
    out = tmp_path / "out"
    task = api.plan(objects, out, {}).tasks[0]
    (out / "table").mkdir(parents=True)
    (out / "table" / "table.glb").write_bytes(b"glTF")
    table = StatusTable(out)
    table.update(
        "table",
        state="done",
        input_hash=task["input_hash"],
        options_hash=task["options_hash"],
        outputs="table/table.glb",
        attempts=1,
    )
    said: list[str] = []
    r = run([objects[0][0].path], out, res=32, export="glb", progress=lambda f, m: said.append(m))
    assert r.skipped == ["table"] and r.ok and r.engine_info == {}
    steps = [m.partition(":")[0] for m in said]
    assert steps == ["options", "inputs", "plan", "end"], said
    assert said[2] == "plan: 0 to run, 1 already done"


# -- the command's end -----------------------------------------------------------------------


def test_the_command_summary_and_exit_code(tmp_path):
    from partscale.cli.batch import exit_code, summary

    r = api.BatchResult(
        outdir=tmp_path,
        status=tmp_path / "status.csv",
        done=["a"],
        failed=[("b", "bad\n mesh")],
        slowest=[("b", 2.0), ("a", 1.0)],
        seconds=3.0,
    )
    lines = summary(r)
    assert lines[0].startswith("batch: 1 done, 1 failed, 0 skipped (already done) in 3.0s")
    assert lines[1] == "slowest: b 2.0 s, a 1.0 s"
    assert lines[2] == "failed: b: bad mesh"
    assert exit_code(r) == 1
    assert exit_code(api.BatchResult(tmp_path, tmp_path, interrupted=["a"])) == 130
    assert exit_code(api.BatchResult(tmp_path, tmp_path, done=["a"])) == 0


def test_optional_values_are_the_stages_own_words():
    from partscale.cli.batch import OPTIONAL_VALUES
    from partscale.render import VIEWS
    from partscale.segment import METHODS

    assert set(OPTIONAL_VALUES["--segment"][1]) == set(METHODS)
    assert set(OPTIONAL_VALUES["--render"][1]) == set(VIEWS)


def test_stages_are_the_ones_the_options_use():
    """The template imports these before its workers fork (options as given or checked)."""
    assert job.stages({}) == ["ingest", "edit"]  # the CSDF itself; import reads edit's units
    assert job.stages({"segment": "fast", "export": "glb"}) == [
        "ingest",
        "edit",
        "segment",
        "export",
    ]
    assert job.stages({"segment": False, "export": "csdf, none"}) == ["ingest", "edit"]
    assert job.stages({"recipe": "r.json", "render": True, "export": []}) == [
        "ingest",
        "edit",
        "zones",
        "render",
    ]
    assert job.stages(job.batch_spec({"fit": "1 = 120%", "export": ("png",)})) == [
        "ingest",
        "edit",
        "zones",
        "export",
    ]


def test_a_row_asking_for_more_stages_than_the_batch_gets_them(tmp_path):
    """The batch writes only CSDFs; one row also segments, exports GLB and renders: the
    template imports those stages too, and the row's outputs are all written."""
    table = data_path("kenney/table.glb")
    m = tmp_path / "m.jsonl"
    rows = [
        {"path": str(table), "name": "plain"},
        {"path": str(table), "name": "more", "segment": "fast", "export": "glb", "render": "top"},
    ]
    m.write_text("".join(json.dumps(r) + "\n" for r in rows))
    r = run([m], tmp_path / "out", res=32, workers=1)
    assert r.ok and sorted(r.done) == ["more", "plain"], r.failed
    assert sorted(p.name for p in (tmp_path / "out" / "plain").iterdir()) == ["plain.csdf.npz"]
    assert sorted(p.name for p in (tmp_path / "out" / "more").iterdir()) == [
        "more.glb",
        "more.render-top.png",
    ]


def test_status_table_written_by_shards_in_turn_keeps_every_row(tmp_path):
    """Two processes' tables on one OUTDIR (shards), writing in turn: each write merges the
    other's rows, though a table reads the file again only when someone else wrote it."""
    a, b = StatusTable(tmp_path), StatusTable(tmp_path)
    a.update("one", state="running")
    b.update("two", state="running")
    a.update("one", state="done", outputs="one/one.glb")  # must keep b's row
    b.update("two", state="failed", error='bad, "quoted"\nmesh')  # must keep a's new state
    rows = read_status(tmp_path / "status.csv")
    assert (rows["one"]["state"], rows["one"]["outputs"]) == ("done", "one/one.glb")
    assert (rows["two"]["state"], rows["two"]["error"]) == ("failed", 'bad, "quoted"\nmesh')
    a.update("three", state="running")
    assert set(read_status(tmp_path / "status.csv")) == {"one", "two", "three"}


def test_status_text_is_the_csv_of_every_row(tmp_path):
    """The table's bytes are csv's own for its rows (quotes, commas, new lines), however
    many times rows were written."""
    import csv
    import io

    from partscale.batch.status import COLUMNS

    t = StatusTable(tmp_path)
    for i, error in enumerate(["", "a,b", 'say "x"', "line\nbreak"]):
        t.update(f"n{i}", state="failed" if error else "done", error=error, attempts=1)
    t.update("n0", seconds="1.5")
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=COLUMNS, lineterminator="\n")
    w.writeheader()
    for name in sorted(t.rows):
        w.writerow(t.rows[name])
    assert (tmp_path / "status.csv").read_text() == buf.getvalue()
