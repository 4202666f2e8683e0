"""The Python mirror of the wire protocol agrees with `ipc/layout.json`, which the Rust build
generates from its own types (`thorarena_ipc::describe`): struct sizes, alignments and field
offsets, the numpy dtype of an environment block, the constants, and the G1 joint order."""

from __future__ import annotations

import ctypes
import json
import struct
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from thorarena import protocol
from thorarena.protocol import Layout

REPO = Path(__file__).resolve().parents[3]
LAYOUT_JSON = json.loads((REPO / "ipc" / "layout.json").read_text())

STRUCTS: dict[str, type[ctypes.Structure]] = {
    "Hello": protocol.Hello,
    "Welcome": protocol.Welcome,
    "BatchHeader": protocol.BatchHeader,
    "EnvHeader": protocol.EnvHeader,
    "ActionHeader": protocol.ActionHeader,
}


def example_layout() -> Layout:
    e = LAYOUT_JSON["example"]
    return Layout(
        n_envs=e["n_envs"], n_joints=e["n_joints"], n_refs=e["n_refs"], n_inputs=e["n_inputs"]
    )


def test_every_rust_struct_has_a_python_mirror() -> None:
    assert set(LAYOUT_JSON["structs"]) == set(STRUCTS)


@pytest.mark.parametrize("name", sorted(STRUCTS))
def test_ctypes_structs_match_size_alignment_and_every_field(name: str) -> None:
    want = LAYOUT_JSON["structs"][name]
    cls = STRUCTS[name]
    assert ctypes.sizeof(cls) == want["size"]
    assert ctypes.alignment(cls) == want["align"]
    got = [
        {"name": field, "offset": getattr(cls, field).offset, "size": getattr(cls, field).size}
        for field, *_ in cls._fields_
    ]
    assert got == want["fields"]
    if want["type_name"]:
        assert getattr(cls, "type_name")() == want["type_name"]  # noqa: B009


@pytest.mark.parametrize("name", ["BatchHeader", "EnvHeader", "ActionHeader"])
def test_header_dtypes_match_the_rust_headers(name: str) -> None:
    want = LAYOUT_JSON["structs"][name]
    dtype = {
        "BatchHeader": protocol.BATCH_HEADER_DTYPE,
        "EnvHeader": protocol.ENV_HEADER_DTYPE,
        "ActionHeader": protocol.ACTION_HEADER_DTYPE,
    }[name]
    assert dtype.itemsize == want["size"]
    assert [(n, off, sub.itemsize) for n, (sub, off) in fields(dtype).items()] == [
        (f["name"], f["offset"], f["size"]) for f in want["fields"]
    ]


def test_constants_are_the_rust_ones() -> None:
    assert LAYOUT_JSON["protocol_version"] == protocol.PROTOCOL_VERSION
    for name, value in LAYOUT_JSON["constants"].items():
        assert getattr(protocol, name) == value, name
    assert LAYOUT_JSON["structs"]["BatchHeader"]["size"] == protocol.BATCH_HEADER_BYTES
    assert LAYOUT_JSON["structs"]["EnvHeader"]["size"] == protocol.ENV_HEADER_BYTES
    assert LAYOUT_JSON["structs"]["ActionHeader"]["size"] == protocol.ACTION_HEADER_BYTES


def test_array_tables_are_the_rust_ones() -> None:
    def table(rows: list[dict[str, Any]]) -> list[tuple[str, int, int]]:
        return [(r["name"], r["fixed"], r["per_joint"]) for r in rows]

    assert list(protocol.ENV_ARRAYS) == table(LAYOUT_JSON["env_arrays"])
    assert list(protocol.REF_ARRAYS) == table(LAYOUT_JSON["ref_arrays"])


def test_example_layout_sizes_match() -> None:
    e = LAYOUT_JSON["example"]
    layout = example_layout()
    names = ("ref_offset", "ref_stride", "env_stride", "inputs_offset", "inputs_bytes")
    for name in (*names, "obs_bytes", "action_bytes"):
        assert getattr(layout, name) == e[name], name
    assert layout.obs_words * 8 == e["obs_bytes"]
    assert layout.action_words * 8 == e["action_bytes"]
    got = [{"name": f.name, "offset": f.offset, "len": f.len} for f in layout.env_fields()]
    assert got == e["env_fields"]


def fields(dtype: np.dtype) -> dict[str, tuple[np.dtype, int]]:
    """A structured dtype's fields: name -> (dtype, byte offset)."""
    assert dtype.fields is not None
    return {name: (f[0], f[1]) for name, f in dtype.fields.items()}


def dtype_offset(layout: Layout, name: str) -> tuple[int, int]:
    """(byte offset, f64 count) of a layout.json field name in `Layout.env_dtype`."""
    env = fields(layout.env_dtype)
    if name.startswith("reference["):
        index, field = name.removeprefix("reference[").split("].")
        sub, offset = fields(layout.ref_dtype)[field]
        base = env["reference"][1] + int(index) * layout.ref_dtype.itemsize
        return base + offset, sub.itemsize // 8
    sub, offset = env[name]
    return offset, sub.itemsize // 8


def test_env_dtype_offsets_and_itemsize_match() -> None:
    layout = example_layout()
    e = LAYOUT_JSON["example"]
    assert layout.env_dtype.itemsize == e["env_stride"]
    assert layout.ref_dtype.itemsize == e["ref_stride"]
    env = fields(layout.env_dtype)
    assert env["reference"][1] == e["ref_offset"]
    assert env["reference"][0].shape == (e["n_refs"],)
    for field in e["env_fields"]:
        assert dtype_offset(layout, field["name"]) == (field["offset"], field["len"]), field["name"]
    for field in LAYOUT_JSON["structs"]["EnvHeader"]["fields"]:
        sub, offset = env[field["name"]]
        assert (offset, sub.itemsize) == (field["offset"], field["size"])


def test_obs_view_reads_values_written_at_the_json_offsets() -> None:
    """Writes every field of a batch at the offsets of layout.json with `struct`, then reads
    it back through the zero-copy numpy view."""
    layout = example_layout()
    e = LAYOUT_JSON["example"]
    header = {f["name"]: f for f in LAYOUT_JSON["structs"]["EnvHeader"]["fields"]}
    raw = bytearray(layout.obs_bytes)
    for env in range(layout.n_envs):
        base = protocol.BATCH_HEADER_BYTES + env * e["env_stride"]
        struct.pack_into("=Q", raw, base + header["episode_id"]["offset"], 100 + env)
        struct.pack_into("=I", raw, base + header["flags"]["offset"], protocol.FLAG_ACTIVE)
        for k, field in enumerate(e["env_fields"]):
            values = [env * 1000.0 + k + 0.5 * i for i in range(field["len"])]
            struct.pack_into(f"={field['len']}d", raw, base + field["offset"], *values)
    obs = layout.obs_view(raw)
    assert obs.shape == (layout.n_envs,)
    assert not obs.flags.writeable
    names = [f["name"] for f in e["env_fields"]]
    for env in range(layout.n_envs):
        assert obs["episode_id"][env] == 100 + env
        assert obs["flags"][env] == protocol.FLAG_ACTIVE
        q = names.index("q")
        np.testing.assert_array_equal(obs["q"][env], env * 1000.0 + q + 0.5 * np.arange(29))
        jp = names.index("reference[1].joint_pos")
        np.testing.assert_array_equal(
            obs["reference"]["joint_pos"][env, 1], env * 1000.0 + jp + 0.5 * np.arange(29)
        )
        t = names.index("reference[0].time_s")
        assert obs["reference"]["time_s"][env, 0] == env * 1000.0 + t


def test_action_view_is_the_block_after_the_action_header() -> None:
    layout = example_layout()
    raw = bytearray(layout.action_bytes)
    actions = layout.action_view(raw)
    assert actions.shape == (layout.n_envs, layout.n_joints)
    actions[1, 28] = 2.5
    assert struct.unpack_from("=d", raw, layout.action_bytes - 8) == (2.5,)


def test_welcome_round_trips_through_its_bytes() -> None:
    w = protocol.Welcome(status=protocol.Status.JOINT_COUNT, n_joints=29, control_dt_s=0.02)
    w.action_scale[28] = 0.25
    ctypes.memmove(
        w.message, protocol.to_fixed("héllo", protocol.MESSAGE_BYTES), protocol.MESSAGE_BYTES
    )
    raw = bytes(w)
    fields = {f["name"]: f for f in LAYOUT_JSON["structs"]["Welcome"]["fields"]}
    assert struct.unpack_from("=I", raw, fields["status"]["offset"]) == (2,)
    assert struct.unpack_from("=d", raw, fields["control_dt_s"]["offset"]) == (0.02,)
    assert struct.unpack_from("=d", raw, fields["action_scale"]["offset"] + 28 * 8) == (0.25,)
    assert protocol.from_fixed(protocol.Welcome.from_buffer_copy(raw).message) == "héllo"


def test_fixed_strings_truncate_on_character_boundaries() -> None:
    assert protocol.to_fixed("twist2", 8) == b"twist2\0\0"
    assert protocol.from_fixed(protocol.to_fixed("héé", 4)) == "hé"
    assert len(protocol.to_fixed("x" * 100, protocol.NAME_BYTES)) == protocol.NAME_BYTES


def test_g1_joint_names_are_robot_toml_order() -> None:
    tomllib = pytest.importorskip("tomllib")
    robot = tomllib.loads((REPO / "data" / "robots" / "g1_29dof" / "robot.toml").read_text())
    assert list(protocol.G1_JOINT_NAMES) == [j["name"] for j in robot["joints"]]


def test_a_batch_header_read_in_one_call_gives_every_field_up_to_n_active() -> None:
    header = protocol.BatchHeader(
        magic=protocol.MAGIC, protocol_version=3, command=1, n_envs=4, n_joints=29, n_refs=2,
        env_stride=1000, n_inputs=1432, seq=77, n_active=3,
    )  # fmt: skip
    words = protocol.BATCH_HEADER_WORDS
    assert words.size == protocol.BatchHeader.reserved0.offset
    fields = words.unpack_from(bytes(header))
    assert fields == (protocol.MAGIC, 3, 1, 4, 29, 2, 1000, 1432, 77, 3)
    layout = Layout(n_envs=4, n_joints=29, n_refs=2, n_inputs=1432)
    header.env_stride = layout.env_stride
    assert words.unpack_from(bytes(header))[3:8] == layout.batch_shape
    assert layout.check_batch_header(header) is None
