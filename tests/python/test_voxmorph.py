"""The voxmorph Python module on the AM crop and synthetic grids: arrays in and out
without copies, round trips through nibabel and meshio, deform byte for byte as the
CLI, and bad input raising the CLI's one-line messages."""

import hashlib
import json
import os
import threading
import time
import warnings

import meshio
import nibabel as nib
import numpy as np
import pandas as pd
import pytest
from PIL import Image

import voxmorph
from conftest import AM_ORGANS, cli


# --- Grid: numpy and nibabel ---------------------------------------------------------

def test_grid_from_numpy_keeps_labels_and_affine(am_crop):
    data, affine = am_crop
    g = voxmorph.Grid(data, affine=affine)
    assert g.shape == data.shape
    assert g.labels.dtype == np.uint16
    np.testing.assert_array_equal(g.labels, data)
    np.testing.assert_allclose(g.affine, affine, atol=1e-9)
    np.testing.assert_allclose(g.spacing, nib.affines.voxel_sizes(affine), rtol=1e-12)


def test_grid_from_spacing_alone_is_axis_aligned():
    g = voxmorph.Grid(np.ones((4, 5, 6), np.int32), spacing=(2.0, 3.0, 4.0))
    np.testing.assert_array_equal(g.affine, np.diag([2.0, 3.0, 4.0, 1.0]))


def test_grid_round_trips_through_nibabel(am_crop, tmp_path):
    data, affine = am_crop
    voxmorph.Grid(data, affine=affine).write(str(tmp_path / "ours.nii.gz"))
    back = nib.load(tmp_path / "ours.nii.gz")
    np.testing.assert_array_equal(np.asarray(back.dataobj), data)
    np.testing.assert_allclose(back.affine, affine, atol=1e-4)
    nib.save(nib.Nifti1Image(data, affine), tmp_path / "theirs.nii.gz")
    g = voxmorph.Grid.read(str(tmp_path / "theirs.nii.gz"))
    np.testing.assert_array_equal(g.labels, data)
    np.testing.assert_allclose(g.affine, affine, atol=1e-4)


def test_labels_are_a_view_of_the_grid_storage(am_crop):
    data, affine = am_crop
    g = voxmorph.Grid(data, affine=affine)
    a, b = g.labels, g.labels
    assert a.ctypes.data == b.ctypes.data
    assert np.shares_memory(a, b)
    assert not np.shares_memory(a, data)
    assert a.flags.f_contiguous and a.flags.writeable
    # Writes through the view reach the grid the engines see.
    a[:] = 0
    a[1, 2, 3] = 7
    assert g.statistics()["label"] == [0, 7]
    # The view keeps the grid alive.
    del g, b
    assert a[1, 2, 3] == 7


def test_a_uint16_fortran_array_is_borrowed_not_copied():
    data = np.asfortranarray(np.arange(60, dtype=np.uint16).reshape(3, 4, 5))
    g = voxmorph.Grid(data, spacing=(1, 2, 3))
    assert np.shares_memory(g.labels, data) and g.labels.ctypes.data == data.ctypes.data
    np.testing.assert_array_equal(g.labels, data)
    assert g.labels.flags.writeable
    # The grid reads the array in place: its writes are the grid's.
    data[2, 3, 4] = 1000
    assert g.statistics()["label"][-1] == 1000
    # The grid keeps the array alive.
    view = g.labels
    del data, g
    assert view[2, 3, 4] == 1000
    # A read-only array gives a read-only view.
    frozen = np.zeros((2, 3, 4), np.uint16, order="F")
    frozen.flags.writeable = False
    f = voxmorph.Grid(frozen)
    assert np.shares_memory(f.labels, frozen) and not f.labels.flags.writeable
    # Any other layout or type is copied once, into the grid's own uint16 storage.
    for other in (np.zeros((3, 4, 5), np.uint16), np.zeros((3, 4, 5), np.uint8, order="F"),
                  np.zeros((3, 4, 5), ">u2", order="F"), np.zeros((6, 4, 5), np.uint16, order="F")[::2]):
        copied = voxmorph.Grid(other)
        assert not np.shares_memory(copied.labels, other) and copied.labels.dtype == np.uint16


def test_engines_take_a_borrowed_grid(figure):
    grid = voxmorph.Grid.read(figure["grid"])
    borrowed = voxmorph.Grid(grid.labels, affine=grid.affine)
    assert np.shares_memory(borrowed.labels, grid.labels)
    # The engines that write their own labels work on a copy; the grid is untouched.
    before = grid.labels.copy()
    parts, _ = voxmorph.parts(borrowed, figure["organs"])
    np.testing.assert_array_equal(parts.labels, voxmorph.parts(grid, figure["organs"])[0].labels)
    image = voxmorph.render(borrowed, pose=figure["pose"], organs=figure["organs"], size=(32, 24), cpu=True)
    np.testing.assert_array_equal(image, voxmorph.render(grid, pose=figure["pose"], organs=figure["organs"], size=(32, 24), cpu=True))
    np.testing.assert_array_equal(grid.labels, before)
    assert np.shares_memory(borrowed.labels, grid.labels)
    # The mesher reads it in place.
    c = [n // 2 for n in grid.shape]
    box = np.asfortranarray(grid.labels[c[0] - 12:c[0] + 12, c[1] - 12:c[1] + 12, c[2] - 12:c[2] + 12])
    piece = voxmorph.Grid(box, spacing=grid.spacing)
    assert np.shares_memory(piece.labels, box)
    points, tets, labels, report = voxmorph.mesh(piece, 4.0, distances=False)
    assert len(tets) > 0 and report["inverted_tets"] == 0 and report["topology"]["preserved"]


def test_read_and_zeros_fill_the_grid_storage_in_place(figure):
    g = voxmorph.Grid.read(figure["grid"])
    assert g.labels.ctypes.data == g.labels.ctypes.data
    z = voxmorph.Grid.zeros((3, 4, 5), spacing=(1, 2, 3))
    z.labels[...] = np.arange(60).reshape(3, 4, 5)
    np.testing.assert_array_equal(z.labels, np.arange(60).reshape(3, 4, 5))


def test_statistics_make_a_pandas_table_with_masses(am_crop):
    data, affine = am_crop
    g = voxmorph.Grid(data, affine=affine)
    table = pd.DataFrame(g.statistics(voxmorph.OrganTable(AM_ORGANS)))
    assert table["voxels"].sum() == data.size
    counts = np.bincount(data.ravel())
    for row in table.itertuples():
        assert row.voxels == counts[row.label]
    named = table.dropna(subset=["mass_g"])
    np.testing.assert_allclose(named["mass_g"], named["volume_mm3"] * named["density_g_cm3"] * 1e-3)
    assert (table[table.label == 0]["name"].isna()).all()


def test_organ_table(tmp_path):
    t = voxmorph.OrganTable(AM_ORGANS)
    assert len(t) > 100 and 1 in t and 0 not in t
    first = next(iter(t.names))
    assert t[first]["name"] == t.names[first] and t[first]["density_g_cm3"] > 0
    with pytest.raises(KeyError):
        t[0]
    bad = tmp_path / "bad.dat"
    bad.write_text("1 skin 2 -1.0\n")
    with pytest.raises(ValueError, match=f"^{bad}"):
        voxmorph.OrganTable(str(bad))


# --- deform: the CLI's run --------------------------------------------------------------

def test_deform_is_byte_identical_to_the_cli(figure, tmp_path):
    # The stick figure's arm changes its body's volume by about 2 %: forced.
    cli("deform", figure["grid"], "--organs", figure["organs"], "--pose", figure["pose"], "--cpu", "--preserve-volumes", "--force",
        "-o", str(tmp_path / "cli.nii.gz"), "-q")
    grid = voxmorph.Grid.read(figure["grid"])
    with open(figure["pose"]) as f:
        pose = json.load(f)
    posed, report = voxmorph.deform(grid, pose, organs=voxmorph.OrganTable(figure["organs"]), preserve_volumes=True, cpu=True,
                                   force=True)
    # The posed grid out, and into a Grid again, without a copy.
    again = voxmorph.Grid(posed.labels, affine=posed.affine)
    assert np.shares_memory(again.labels, posed.labels)
    again.write(str(tmp_path / "python.nii.gz"))
    assert (tmp_path / "python.nii.gz").read_bytes() == (tmp_path / "cli.nii.gz").read_bytes()
    # Paths in and out: the CLI's own run.
    voxmorph.deform(figure["grid"], figure["pose"], organs=figure["organs"], preserve_volumes=True, cpu=True, force=True,
                    output=str(tmp_path / "paths.nii.gz"))
    assert (tmp_path / "paths.nii.gz").read_bytes() == (tmp_path / "cli.nii.gz").read_bytes()
    assert report["input"] == figure["grid"]
    assert report["whole_body"]["voxels_before"] > 0
    labels = pd.DataFrame(report["labels"])
    assert {"label", "voxels_before", "voxels_after"} <= set(labels.columns)
    assert sorted(os.listdir(tmp_path)) == ["cli.nii.gz", "paths.nii.gz", "python.nii.gz"]


def test_skin_cover_off_is_the_clis_no_skin_cover(figure, tmp_path):
    cli("deform", figure["grid"], "--organs", figure["organs"], "--pose", figure["pose"], "--cpu", "--preserve-volumes", "--force",
        "--no-skin-cover", "-o", str(tmp_path / "cli.nii.gz"), "-q")
    _, report = voxmorph.deform(figure["grid"], figure["pose"], organs=figure["organs"], preserve_volumes=True, skin_cover=False,
                                cpu=True, force=True, output=str(tmp_path / "python.nii.gz"))
    assert (tmp_path / "python.nii.gz").read_bytes() == (tmp_path / "cli.nii.gz").read_bytes()
    assert "skin_cover" not in report


def test_warnings_raise_as_errors_under_an_error_filter(figure, tmp_path):
    # An organ table without label 1: the run warns that its mass is left out.
    with open(figure["organs"]) as f:
        lines = [line for line in f if not line.startswith("1 ")]
    (tmp_path / "less.dat").write_text("".join(lines))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        voxmorph.deform(figure["grid"], figure["pose"], organs=str(tmp_path / "less.dat"), cpu=True, force=True)
    assert any("labels without a name in the organ table: 1 (" in str(w.message) for w in caught)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(RuntimeWarning):
            voxmorph.deform(figure["grid"], figure["pose"], organs=str(tmp_path / "less.dat"), cpu=True, force=True)


def test_deform_takes_a_prepared_state(figure, tmp_path):
    state = str(tmp_path / "figure.vxprep")
    cli("prepare", figure["grid"], "--organs", figure["organs"], "--pose", figure["pose"], "-o", state, "-q")
    common = dict(organs=figure["organs"], preserve_volumes=True, cpu=True, force=True)
    voxmorph.deform(figure["grid"], figure["pose"], output=str(tmp_path / "without.nii.gz"), **common)
    voxmorph.deform(figure["grid"], figure["pose"], prepared=state, output=str(tmp_path / "with.nii.gz"), **common)
    assert (tmp_path / "with.nii.gz").read_bytes() == (tmp_path / "without.nii.gz").read_bytes()
    # A Grid in memory has no file for the state to be checked against.
    with pytest.raises(ValueError, match="prepared"):
        voxmorph.deform(voxmorph.Grid.read(figure["grid"]), figure["pose"], prepared=state, **common)
    # A state of another grid: the CLI's one-line refusal, nothing written.
    other = tmp_path / "other.nii.gz"
    g = voxmorph.Grid.read(figure["grid"])
    g.labels[0, 0, 0] = 1
    g.write(str(other))
    with pytest.raises(ValueError, match="prepared from another grid"):
        voxmorph.deform(str(other), figure["pose"], prepared=state, output=str(tmp_path / "stale.nii.gz"), **common)
    assert not (tmp_path / "stale.nii.gz").exists()


def test_deform_of_a_grid_in_memory_writes_no_scratch_file(figure, tmp_path, monkeypatch):
    # The Grid is read where it lies and the posed grid comes back from memory: nothing is
    # made in the temporary folder (TMPDIR names a folder that does not exist, so creating
    # anything there fails) nor beside the output, where only the output and its atomic
    # temporary appear while the run works.
    monkeypatch.setenv("TMPDIR", str(tmp_path / "absent"))
    out = tmp_path / "out"
    out.mkdir()
    monkeypatch.chdir(out)
    owned = voxmorph.Grid.read(figure["grid"])
    borrowed = voxmorph.Grid(np.array(owned.labels, order="F"), affine=owned.affine)
    assert not np.shares_memory(borrowed.labels, owned.labels)
    with open(figure["pose"]) as f:
        pose = json.load(f)
    common = dict(organs=voxmorph.OrganTable(figure["organs"]), preserve_volumes=True, cpu=True, force=True)
    seen, running = set(), threading.Event()

    def watch():
        while running.is_set():
            seen.update(os.listdir(out))
            time.sleep(0.001)

    running.set()
    watcher = threading.Thread(target=watch)
    watcher.start()
    try:
        posed, report = voxmorph.deform(owned, pose, **common)
        again, report_again = voxmorph.deform(borrowed, figure["pose"], output=str(out / "posed.nii.gz"), **common)
        streamed, _ = voxmorph.deform(borrowed, pose, organs=figure["organs"], cpu=True, force=True,
                                      output=str(out / "streamed.nii"))
        # Out of core: the source read slab by slab from memory.
        windowed, _ = voxmorph.deform(borrowed, pose, organs=figure["organs"], cpu=True, force=True, max_memory=256)
    finally:
        running.clear()
        watcher.join()
    assert not (tmp_path / "absent").exists()
    assert sorted(os.listdir(out)) == ["posed.nii.gz", "streamed.nii"]
    assert all(n in ("posed.nii.gz", "streamed.nii") or
               (n.startswith(f".tmp-{os.getpid()}-") and n.endswith((".posed.nii.gz", ".streamed.nii"))) for n in seen), seen
    # The same posed grid whether the Grid owns its labels or borrows numpy's, and its file
    # is what the module returns.
    np.testing.assert_array_equal(posed.labels, again.labels)
    np.testing.assert_array_equal(voxmorph.Grid.read(str(out / "posed.nii.gz")).labels, again.labels)
    np.testing.assert_array_equal(voxmorph.Grid.read(str(out / "streamed.nii")).labels, streamed.labels)
    # Provenance: the files given as paths by their digests, a pose dict by its text's; a
    # Grid in memory has no file, only its name in "input".
    assert report["input"] == figure["grid"] and report_again["input"] == "grid"
    assert report["output"] == "" and report_again["output"] == str(out / "posed.nii.gz")
    roles = {d["role"]: d for d in report["provenance"]["inputs"]}
    assert set(roles) == {"pose"} and roles["pose"]["path"] == "pose (dict)" and len(roles["pose"]["sha256"]) == 64
    roles = {d["role"]: d for d in report_again["provenance"]["inputs"]}
    assert set(roles) == {"pose"} and roles["pose"]["path"] == figure["pose"]
    assert roles["pose"]["sha256"] == hashlib.sha256(open(figure["pose"], "rb").read()).hexdigest()
    assert report["provenance"]["working_directory"] == str(out)
    # Streamed slab by slab into memory (no volume correction) as from the file.
    from_file, by_path = voxmorph.deform(figure["grid"], pose, organs=figure["organs"], cpu=True, force=True)
    np.testing.assert_array_equal(streamed.labels, from_file.labels)
    np.testing.assert_array_equal(windowed.labels, from_file.labels)
    roles = {d["role"]: d for d in by_path["provenance"]["inputs"]}
    assert set(roles) == {"grid", "organs", "pose"}
    assert roles["grid"]["sha256"] == hashlib.sha256(open(figure["grid"], "rb").read()).hexdigest()


# --- Posing, parts ------------------------------------------------------------------------

def test_posing_frames_follow_the_joints(figure):
    grid = voxmorph.Grid.read(figure["grid"])
    posing = voxmorph.Posing(grid, figure["pose"], organs=figure["organs"])
    first = posing.frame()
    points, tets, labels = posing.transfer_mesh
    assert first["positions"].shape == points.shape and tets.shape[1] == 4 and len(labels) == len(tets)
    assert first["inverted_tets"] < len(tets) // 100 and first["vertices_outside_cage"] >= 0
    posing.set_joints({"right_shoulder": {"abduction": 60}})
    second = posing.frame()
    assert np.abs(second["positions"] - first["positions"]).max() > 1.0
    for v in second["label_volumes"].values():
        assert abs(v["change_percent"]) < 20
    posed = posing.rasterize(cpu=True)
    assert posed.labels.max() == grid.labels.max()
    assert "selections" in posing.pose
    assert second["bones_through_each_other"] is None
    posing.set_joints({"right_shoulder": {"abduction": -30}})  # the hanging arm into the pelvis
    assert "pass through each other" in posing.frame()["bones_through_each_other"]


def test_parts_and_joints(figure):
    grid = voxmorph.Grid.read(figure["grid"])
    parts, joints = voxmorph.parts(grid, figure["organs"])
    assert parts.shape == grid.shape
    np.testing.assert_array_equal(parts.affine, grid.affine)
    assert len(joints) == 14 and joints[2]["name"] == "right_shoulder"
    assert ((parts.labels > 0) == (grid.labels > 0)).all()


# --- mesh, remesh, render -------------------------------------------------------------------

def test_mesh_and_remesh_round_trip_through_meshio(am_crop, tmp_path):
    data, affine = am_crop
    shifted = affine.copy()
    shifted[:3, 3] = nib.affines.apply_affine(affine, [48, 24, 0])
    small = voxmorph.Grid(data[48:80, 24:52, :], affine=shifted)
    points, tets, labels, report = voxmorph.mesh(small, 4.0, organs=AM_ORGANS, distances=False)
    assert points.shape[1] == 3 and tets.shape[1] == 4 and len(labels) == len(tets)
    assert (labels > 0).all() and tets.max() < len(points)
    assert report["inverted_tets"] == 0 and report["topology"]["preserved"]
    assert report["tets"]["output"] == len(tets) and report["vertices"] == len(points)
    meshio.write(tmp_path / "mesh.vtu", meshio.Mesh(points, [("tetra", tets)], cell_data={"label": [labels]}))
    back = meshio.read(tmp_path / "mesh.vtu")
    np.testing.assert_allclose(back.points, points)
    np.testing.assert_array_equal(back.cells_dict["tetra"], tets)
    # The mesh lies over the grid in the world frame.
    lo, hi = points.min(axis=0), points.max(axis=0)
    corners = nib.affines.apply_affine(small.affine, [[0, 0, 0], [31, 27, 9]])
    spacing = np.array(small.spacing)
    assert (lo >= corners.min(axis=0) - spacing).all() and (hi <= corners.max(axis=0) + spacing).all()
    p2, t2, l2, r2 = voxmorph.remesh(points, tets, labels, 5.0, distances=False)
    assert len(t2) > 0 and set(np.unique(l2)) <= set(np.unique(labels))


def test_mesh_takes_the_clis_sizing_bound_and_sliver_options(am_crop, tmp_path):
    data, affine = am_crop
    nib.save(nib.Nifti1Image(data[48:80, 24:52, :], affine), tmp_path / "small.nii.gz")
    small = voxmorph.Grid.read(tmp_path / "small.nii.gz")  # the CLI's grid to the last bit of its affine
    args = dict(size_boundary=4.0, size_interior=12.0, hausdorff=0.3, steiner_angle=10.0, distances=False)
    points, tets, labels, report = voxmorph.mesh(small, **args)
    cli_report = json.loads(cli("mesh", str(tmp_path / "small.nii.gz"), "--size-boundary", "4", "--size-interior", "12",
                                "--hausdorff", "0.3", "--steiner-angle", "10", "--no-distance", "-o",
                                str(tmp_path / "small.mesh"), "--report", "-").stdout)
    assert report["tets"]["output"] == cli_report["tets"]["output"] == len(tets)
    assert report["sizing_field_mm"] == cli_report["sizing_field_mm"] and report["sizing_field_mm"]["min"] == 4.0
    assert report["target_edge_length_mm"] == 4.0 and report["topology"]["preserved"]
    uniform = voxmorph.mesh(small, 4.0, distances=False)[3]
    assert report["tets"]["output"] < uniform["tets"]["output"]
    # The remesher of a mesh takes them too; sizing from its interfaces.
    coarser = voxmorph.remesh(points, tets, labels, size_boundary=5.0, size_interior=15.0, hausdorff=0.0, steiner_angle=0.0,
                              distances=False)[3]
    assert coarser["sizing_field_mm"]["max"] <= 15.0 and coarser["steiner_points"]["inserted"] == 0
    for kwargs, message in [(dict(size_boundary=4.0), "size_interior: adaptive sizing takes both"),
                            (dict(l=4.0, size_boundary=4.0, size_interior=8.0), "l: is not taken with adaptive sizing"),
                            (dict(size_boundary=8.0, size_interior=4.0), r"size_interior: l_I = 4 mm is shorter than size_boundary l_B = 8 mm"),
                            (dict(), "l: a target edge length is required"),
                            (dict(l=4.0, hausdorff=11.0), r"hausdorff: must be a number of l in \[0, 10\]; got 11"),
                            (dict(l=4.0, steiner_angle=-1.0), r"steiner_angle: must be a number of degrees in \[0, 60\]")]:
        with pytest.raises(ValueError, match=message):
            voxmorph.mesh(small, **kwargs)


def test_render_gives_an_rgb_array(figure, tmp_path):
    grid = voxmorph.Grid.read(figure["grid"])
    image = voxmorph.render(grid, organs=figure["organs"], camera="azimuth=20,elevation=10", size=(64, 48), cpu=True)
    assert image.shape == (48, 64, 3) and image.dtype == np.uint8
    assert image.reshape(-1, 3).std(axis=0).max() > 0
    Image.fromarray(image).save(tmp_path / "figure.png")
    posed = voxmorph.render(grid, pose=figure["pose"], organs=figure["organs"], size=(64, 48), cuts=["x>0mm"], cpu=True)
    assert posed.shape == (48, 64, 3)
    faces = voxmorph.render(grid, organs=figure["organs"], camera="azimuth=20,elevation=10", size=(64, 48), shading="faces", cpu=True)
    assert faces.shape == image.shape and (faces != image).any()
    with pytest.raises(ValueError):
        voxmorph.render(grid, size=(64, 48), shading="flat", cpu=True)


# --- the GIL, help ----------------------------------------------------------------------------

def test_long_calls_release_the_gil(figure):
    grid = voxmorph.Grid.read(figure["grid"])
    ticks = 0
    worker = threading.Thread(target=lambda: voxmorph.Posing(grid, figure["pose"], organs=figure["organs"]))
    worker.start()
    while worker.is_alive():
        ticks += 1
    worker.join()
    assert ticks > 10000


def test_help_explains_every_argument():
    doc = voxmorph.deform.__doc__
    for argument in ("grid", "pose", "organs", "preserve_volumes", "skin_cover", "prepared", "output", "cpu", "samples", "rigid_bones", "force",
                     "max_body_change", "max_bone_change", "max_bone_overlap", "max_tissue_overlap", "allow_growth", "max_memory"):
        assert f"{argument}:" in doc or f"{argument}," in doc, argument
    for name in ("Grid", "OrganTable", "Posing", "mesh", "remesh", "render", "parts"):
        assert getattr(voxmorph, name).__doc__


def test_stubs_lie_beside_the_module():
    stub = os.path.join(os.path.dirname(voxmorph.__file__), "voxmorph.pyi")
    text = open(stub).read()
    for name in ("class Grid", "class OrganTable", "class Posing", "def deform", "def mesh", "def remesh", "def render", "def parts"):
        assert name in text


# --- bad input -----------------------------------------------------------------------------------

def test_a_missing_file_is_an_oserror_naming_it(tmp_path):
    missing = str(tmp_path / "missing.nii.gz")
    with pytest.raises(FileNotFoundError, match=f"^{missing}: "):
        voxmorph.Grid.read(missing)
    with pytest.raises(OSError, match="nothing.dat"):
        voxmorph.OrganTable(str(tmp_path / "nothing.dat"))


def test_a_corrupt_grid_is_a_valueerror_naming_it(tmp_path):
    bad = tmp_path / "bad.nii"
    bad.write_bytes(b"\x5c\x01\x00\x00" + b"\x00" * 100)
    with pytest.raises(ValueError, match=f"^{bad}: "):
        voxmorph.Grid.read(str(bad))


def test_bad_arrays_are_valueerrors():
    with pytest.raises(ValueError, match="labels: a float64 array"):
        voxmorph.Grid(np.zeros((2, 2, 2)))
    with pytest.raises(ValueError, match=r"^labels: values span -1..-1; labels must lie in 0..65535$"):
        voxmorph.Grid(-np.ones((2, 2, 2), np.int32))
    with pytest.raises(ValueError, match="3-D array"):
        voxmorph.Grid(np.zeros((2, 2), np.uint8))
    with pytest.raises(ValueError, match="affine: .*not orthogonal"):
        voxmorph.Grid(np.zeros((2, 2, 2), np.uint8), affine=[[1, 1, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
    with pytest.raises(ValueError, match="tets: tet 0 refers to vertex 9"):
        voxmorph.remesh(np.zeros((4, 3)), [[0, 1, 2, 9]], [1], 1.0)


def test_a_bad_pose_is_a_valueerror_with_the_cli_message(figure):
    grid = voxmorph.Grid.read(figure["grid"])
    with pytest.raises(ValueError, match=r"^pose: joint 'right_elbow' flexion 170 is outside its range \[0, 150\] degrees$"):
        voxmorph.deform(grid, {"joints": {"right_elbow": {"flexion": 170}}}, organs=figure["organs"], cpu=True)
    with pytest.raises(ValueError, match=r"^pose: the bones of the right_\w+ and the left_\w+ pass through each other \(.*with right_hip as posed; nothing written"):
        voxmorph.deform(grid, {"joints": {"right_hip": {"abduction": -30}}}, organs=figure["organs"], cpu=True)
    with pytest.raises(ValueError, match=r"^pose: a pose with joints or body parts needs the grid's organ table \(--organs\) to find the bones$"):
        voxmorph.Posing(grid, {"joints": {"right_shoulder": {"abduction": 30}}})
    with pytest.raises(ValueError, match=r"^bone_gap: needs articulated=True$"):
        voxmorph.deform(grid, {"joints": {"right_wrist": {"flexion": 30}}}, organs=figure["organs"], cpu=True, bone_gap=5)
    with pytest.raises(ValueError, match=r"^bone_gap: -1\.0+ mm is not in \[0, 100\]$"):
        voxmorph.deform(grid, {"joints": {"right_wrist": {"flexion": 30}}}, organs=figure["organs"], cpu=True, articulated=True, bone_gap=-1)
