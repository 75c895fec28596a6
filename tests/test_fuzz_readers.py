"""Seeded mutation tests of the readers: ASF, AMC, clips.csv and saved maps.

Each case mutates a real file (read from the data directory at run time, written to
``tmp_path``) and reads it the way the command line does. The outcome must be a clean
result (finite numbers) or one :class:`DataFileError` naming the mutated file: never
another exception, never a message blaming another file.
"""

from __future__ import annotations

import random
import warnings

import numpy as np
import pytest

from tests.fuzz_mutations import ASF_MUTATORS, CSV_MUTATORS, mutate, mutate_npz, zip_bomb
from upm.core.errors import DataFileError

N_CASES = 300


def _assert_names(exc: DataFileError, path) -> None:
    assert exc.path == str(path), f"error blames {exc.path}, not {path}: {exc}"
    assert "\n" not in str(exc)


@pytest.fixture(scope="module")
def asf_bytes(data_dir):
    return (data_dir / "02" / "02.asf").read_bytes()


@pytest.fixture(scope="module")
def amc_bytes(data_dir):
    """The first 12 frames of 02_01 (a short but real AMC)."""
    lines = (data_dir / "02" / "02_01.amc").read_bytes().split(b"\n")
    starts = [i for i, line in enumerate(lines) if line.strip() == b"13"]
    assert lines.count(b"2\r") + lines.count(b"2") == 1
    return b"\n".join(lines[:starts[0]]) + b"\n"


def test_mutated_asf_is_read_or_refused_naming_it(tmp_path, asf_bytes):
    from humanoid_xml.validate import check_skeleton
    from upm.motion.asf import read_asf

    rng = random.Random(15)
    outcomes = {"read": 0, "refused": 0}
    for case in range(N_CASES):
        path = tmp_path / f"case{case}.asf"
        path.write_bytes(mutate(asf_bytes, rng, ASF_MUTATORS))
        try:
            skeleton = read_asf(path)
            check_skeleton(skeleton)
        except DataFileError as exc:
            _assert_names(exc, path)
            outcomes["refused"] += 1
            continue
        assert np.all(np.isfinite(skeleton.lengths_m)) and np.all(skeleton.lengths_m < 100)
        outcomes["read"] += 1
    assert outcomes["refused"] > N_CASES // 3 and outcomes["read"] > 10, outcomes


def test_mutated_asf_builds_a_humanoid_or_names_the_asf(tmp_path, asf_bytes, monkeypatch):
    """The model path the commands share (read the ASF, check it, build the MJCF, compile
    it in MuJoCo for the gains): a refusal names the ASF in one line; a degenerate bone (a
    zero, vanishing or astronomic length, or a zero direction) is always refused; a model
    that is built loads in MuJoCo with a hinge per declared DOF and a finite mass. One
    mutation per case: a third or more of the single absurd numbers (in an id, the root's
    position, an axis angle or a limit, where 0 or 1e-300 is still valid) leave a skeleton
    the humanoid can be built from."""
    from humanoid_xml import load_model, subject_model_path
    from tests.fuzz_mutations import absurd_number, all_numbers, degenerate_bone
    from upm.motion.asf import read_asf

    monkeypatch.setenv("UPM_CACHE", str(tmp_path / "cache"))
    rng = random.Random(1515)
    outcomes = {"built": 0, "refused": 0}
    for case in range(36):
        mutator = rng.choice((degenerate_bone, absurd_number, all_numbers))
        path = tmp_path / f"case{case}.asf"
        path.write_bytes(mutate(asf_bytes, rng, (mutator,), rounds=1))
        try:
            model = load_model(subject_model_path(path))
        except DataFileError as exc:
            _assert_names(exc, path)
            outcomes["refused"] += 1
            continue
        assert mutator is not degenerate_bone, f"case {case}: a degenerate bone was built"
        assert model.nu == int(read_asf(path).declared.sum()) == 45
        assert np.isfinite(model.body_mass).all() and 40 < model.body_mass.sum() < 150
        outcomes["built"] += 1
    assert outcomes["built"] >= 3 and outcomes["refused"] >= 18, outcomes


@pytest.mark.parametrize("text, message", [
    ("dof rx ry rz", "no joint strength"),
    ("length 0", "m long"),
])
def test_humanoid_refuses_a_degenerate_hand_naming_the_asf_line(tmp_path, asf_bytes, text,
                                                                  message):
    from humanoid_xml import build_mjcf
    from upm.motion.asf import read_asf

    lines = asf_bytes.decode().splitlines()
    begin = next(i for i, line in enumerate(lines) if line.strip() == "name rhand") - 2
    end = next(i for i in range(begin, len(lines)) if lines[i].strip() == "end")
    key = text.split()[0]
    at = next(i for i in range(begin, end) if lines[i].split()[:1] == [key])
    lines[at] = "    " + text
    if key == "dof":  # a third limits pair for the third dof
        limits = next(i for i in range(begin, end) if lines[i].split()[:1] == ["limits"])
        lines.insert(limits + 1, "        (-10 10)")
    path = tmp_path / "02.asf"
    path.write_text("\n".join(lines))
    with pytest.raises(DataFileError, match=message) as info:
        build_mjcf(read_asf(path))
    assert info.value.path == str(path) and info.value.line == begin + 1  # its "begin"


def test_mutated_amc_is_read_or_refused_naming_it(tmp_path, catalog, amc_bytes):
    from upm.motion.amc import read_amc

    skeleton = catalog.skeleton("02")
    rng = random.Random(150)
    outcomes = {"read": 0, "refused": 0}
    for case in range(N_CASES):
        path = tmp_path / f"case{case}.amc"
        path.write_bytes(mutate(amc_bytes, rng))
        try:
            motion = read_amc(path, skeleton)
        except DataFileError as exc:
            _assert_names(exc, path)
            outcomes["refused"] += 1
            continue
        assert np.all(np.isfinite(motion.posture_deg)) and np.all(np.isfinite(motion.root))
        assert np.all(np.abs(motion.posture_deg) <= 1e6)
        outcomes["read"] += 1
    assert outcomes["refused"] > N_CASES // 3 and outcomes["read"] > 10, outcomes


@pytest.mark.parametrize("number", ["\u00b2", "\u00b9", "9" * 5000, "1234567890"])
def test_amc_frame_numbers_are_short_ascii_digits(tmp_path, catalog, amc_bytes, number):
    from upm.motion.amc import read_amc

    path = tmp_path / "bad.amc"
    lines = amc_bytes.splitlines()
    at = lines.index(b"2")
    lines[at] = number.encode()
    path.write_bytes(b"\n".join(lines))
    with pytest.raises(DataFileError) as info:
        read_amc(path, catalog.skeleton("02"))
    _assert_names(info.value, path)


def test_mutated_clips_csv_is_read_or_refused_naming_it(tmp_path, data_dir):
    from upm.motion.catalog import Catalog

    source = (data_dir / "clips.csv").read_bytes().split(b"\n")
    csv_bytes = b"\n".join(source[:12]) + b"\n"
    (tmp_path / "02").mkdir()
    (tmp_path / "02" / "02_01.amc").write_bytes(b"1\n")  # the catalogue does not read it
    rng = random.Random(1500)
    outcomes = {"read": 0, "refused": 0}
    path = tmp_path / "clips.csv"
    for _ in range(N_CASES):
        path.write_bytes(mutate(csv_bytes, rng, CSV_MUTATORS))
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                catalog = Catalog(tmp_path)
        except DataFileError as exc:
            _assert_names(exc, path)
            outcomes["refused"] += 1
            continue
        assert all(0 < info.fps <= 10000 for info in catalog)
        outcomes["read"] += 1
    assert outcomes["refused"] > N_CASES // 4 and outcomes["read"] > 10, outcomes


@pytest.fixture(scope="module")
def map_bytes(tmp_path_factory, catalog):
    from upm.maps.posture_map import UniformPostureMap

    x = catalog.load("02_01").posture_deg[::20]
    path = tmp_path_factory.mktemp("map") / "map.npz"
    UniformPostureMap(radius_deg=40.0, passes=1, seed=0).fit(x, clip_names=["02_01"]).save(path)
    return path.read_bytes()


def test_mutated_map_is_loaded_or_refused_naming_it(tmp_path, map_bytes):
    from upm.commands.train import summary_rows
    from upm.maps.map_file import load_map

    rng = random.Random(15000)
    outcomes = {"loaded": 0, "refused": 0}
    for case in range(N_CASES):
        path = tmp_path / f"case{case}.npz"
        path.write_bytes(mutate_npz(map_bytes, rng))
        try:
            posture_map = load_map(path)
        except DataFileError as exc:
            _assert_names(exc, path)
            outcomes["refused"] += 1
            continue
        summary_rows(posture_map)  # what map-info and train print
        outcomes["loaded"] += 1
    assert outcomes["refused"] > N_CASES // 2, outcomes


def test_a_zip_bomb_map_is_refused_unread(tmp_path, map_bytes):
    from upm.maps.map_file import load_map

    path = tmp_path / "bomb.npz"
    path.write_bytes(zip_bomb(map_bytes, megabytes=64))
    with pytest.raises(DataFileError, match="zip bomb") as info:
        load_map(path)
    _assert_names(info.value, path)


def test_a_map_member_with_an_unbalanced_npy_header_names_the_map(tmp_path, map_bytes):
    """numpy parses the .npy header with Python's tokenizer: an unclosed bracket there
    raises ``tokenize.TokenError`` (found by a 10,000-case campaign)."""
    import io
    import zipfile

    from upm.maps.map_file import load_map

    out = io.BytesIO()
    with zipfile.ZipFile(io.BytesIO(map_bytes)) as src, zipfile.ZipFile(out, "w") as dst:
        for info in src.infolist():
            data = src.read(info)
            if info.filename == "neurons_body.npy":
                data = data.replace(b"'shape': (", b"'shape': ((", 1)
            dst.writestr(info.filename, data)
    path = tmp_path / "unbalanced.npz"
    path.write_bytes(out.getvalue())
    with pytest.raises(DataFileError) as info:
        load_map(path)
    _assert_names(info.value, path)


def test_an_object_array_map_is_refused_never_unpickled(tmp_path, map_bytes):
    import io
    import zipfile

    from tests.fuzz_mutations import object_npy
    from upm.maps.map_file import load_map

    # A protocol-0 pickle stream, written by hand, that exits the process if unpickled.
    boom = b"cbuiltins\nexec\n(Vraise SystemExit('unpickled')\ntR."
    member = object_npy(boom)
    out = io.BytesIO()
    with zipfile.ZipFile(io.BytesIO(map_bytes)) as src, zipfile.ZipFile(out, "w") as dst:
        for info in src.infolist():
            data = member if info.filename == "neurons_body.npy" else src.read(info)
            dst.writestr(info.filename, data)
    path = tmp_path / "pickled.npz"
    path.write_bytes(out.getvalue())
    with pytest.raises(DataFileError, match="never unpickled"):
        load_map(path)


def test_amc_is_read_in_memory_bounded_by_three_times_its_size(tmp_path, catalog, data_dir):
    import tracemalloc

    from upm.motion.amc import read_amc

    text = (data_dir / "02" / "02_01.amc").read_text()
    header, _, body = text.partition("\n1\n")
    frames = ("1\n" + body).split("\n")
    starts = [i for i, line in enumerate(frames) if line.strip().isdigit()]
    block = frames[starts[0]:starts[1]]
    lines = [header]
    for number in range(1, 3001):  # about 2.5 MB
        lines += [str(number)] + block[1:]
    path = tmp_path / "long.amc"
    path.write_text("\n".join(lines) + "\n")
    size = path.stat().st_size
    tracemalloc.start()
    try:
        motion = read_amc(path, catalog.skeleton("02"))
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert motion.n_frames == 3000
    assert peak <= 3 * size, f"peak {peak / size:.2f} x the file size"


def test_model_command_names_a_degenerate_asf(tmp_path, asf_bytes):
    """`upm model --asf` with a zero-length bone: one line naming the ASF, exit 2."""
    import subprocess
    import sys

    lines = asf_bytes.decode().splitlines()
    hand = next(i for i, line in enumerate(lines) if line.strip() == "name rhand")
    at = next(i for i in range(hand, len(lines)) if lines[i].strip().startswith("length"))
    lines[at] = "     length 0"
    path = tmp_path / "my skeleton ñ.asf"
    path.write_text("\n".join(lines))
    result = subprocess.run([sys.executable, "-m", "upm", "model", "--asf", str(path),
                             "--out", str(tmp_path / "m.xml")], capture_output=True, text=True)
    assert result.returncode == 2
    assert len(result.stderr.strip().splitlines()) == 1 and str(path) in result.stderr
    assert "'rhand' is 0 m long" in result.stderr
    assert not (tmp_path / "m.xml").exists()
