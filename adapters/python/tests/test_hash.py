"""`joint_names_hash` is FNV-1a (64 bit) over the names joined by `\\n`, as in
`thorarena_ipc::joint_names_hash` (same published vectors as its Rust unit test)."""

from thorarena.protocol import G1_JOINT_NAMES, joint_names_hash


def test_fnv1a_published_vectors() -> None:
    assert joint_names_hash([]) == 0xCBF29CE484222325  # the offset basis
    assert joint_names_hash([""]) == 0xCBF29CE484222325
    assert joint_names_hash(["a"]) == 0xAF63DC4C8601EC8C
    assert joint_names_hash(["foobar"]) == 0x85944171F73967E8


def test_names_are_joined_by_newlines() -> None:
    assert joint_names_hash(["foo", "bar"]) == joint_names_hash(["foo\nbar"])


def test_order_matters() -> None:
    assert joint_names_hash(["a", "b"]) != joint_names_hash(["b", "a"])
    reordered = list(G1_JOINT_NAMES)
    reordered[0], reordered[1] = reordered[1], reordered[0]
    assert joint_names_hash(reordered) != joint_names_hash(G1_JOINT_NAMES)


def test_hash_is_a_u64_and_accepts_any_iterable() -> None:
    h = joint_names_hash(iter(G1_JOINT_NAMES))
    assert 0 <= h < 2**64
    assert h == joint_names_hash(tuple(G1_JOINT_NAMES))
