#!/usr/bin/env python3
"""Generate ThorArena's G1 URDF from Unitree's G1 29-DoF rev 1.0 description.

Input: the Unitree description directory (default ``../shared/reference/g1``
relative to the repository root) holding ``g1_29dof_rev_1_0.urdf`` and its STL
meshes in ``meshes/``. Output (default ``data/robots/g1_29dof/g1_29dof.urdf``):
a URDF with

* the same robot tree: every link and joint of the reference, with the same
  names and types; joint ``<origin>``, ``<axis>``, ``<limit>`` and every
  ``<inertial>`` copied *textually* (attribute strings are never re-formatted,
  so the numbers are exactly Unitree's). Fixed links (sensors, logo, head,
  rubber hands, ...) are kept; ThorArena's loader merges them into their parents.
* no meshes, no ``<visual>`` and no ``<mujoco>`` element.
* one primitive ``<collision>`` per link that has a mesh, fitted to that mesh in
  code (see "Fitting" below), named after its shape kind ("box", "capsule").
  Links without a mesh get no collision.
* the feet (``*_ankle_roll_link``) keep the reference's four 5 mm sole spheres
  verbatim, each named ``sole``, plus one box named ``foot`` covering the foot.

Fitting. All reference mesh geometries sit at the link origin with no scale
(checked; the script aborts otherwise), so mesh vertices are link-frame points.

* box: axis-aligned in the link frame; centre = centre of the vertices'
  bounding box, size = bounding-box extent times ``SHRINK``. The foot box is
  not shrunk, so that it covers the whole foot, except that its bottom is
  raised to the bottom of the sole spheres (z = -0.035; the mesh's rubber sole
  reaches -0.0354), so the soles stay the lowest contact points.
* capsule: along the mesh's principal axis (largest eigenvalue of the
  area-weighted covariance of the triangle centroids, i.e. independent of how
  finely a region is tessellated). The vertices' bounding box in the principal
  frame gives the long extent L and the two cross extents w1, w2; then
  radius = SHRINK * (w1 + w2) / 4 and the total tip-to-tip length is SHRINK * L,
  centred on that bounding box.

Capsule convention (urdf-rs 0.10 ``<capsule radius length>``, not standard URDF;
urdf-rs only parses the two numbers): the capsule's axis is the local z axis of
its collision ``<origin>``, and ``length`` is the distance between the two
hemisphere centres (cylindrical part only), so the tip-to-tip length is
``length + 2 * radius``. This is how ThorArena's loader reads it
(``half_length = length / 2``), matching rapier's ``Capsule`` and MuJoCo's
``fromto`` capsules. The orientation is written as URDF ``rpy`` (roll 0, pitch
and yaw turning z onto the axis).

Sizes and positions are rounded to 4 decimals. The output is deterministic:
the same input gives the same bytes.

Usage: python3 tools/make_g1_urdf.py [--reference DIR] [--out FILE]

Exit codes: 0 written and verified, 1 input missing or malformed, or the
written file failed verification.
"""

from __future__ import annotations

import argparse
import math
import os
import struct
import sys
import xml.etree.ElementTree as ET
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

REPO_ROOT = Path(__file__).resolve().parent.parent
DEFAULT_REFERENCE = (
    Path(os.environ.get("THORARENA_REFERENCE") or REPO_ROOT.parent / "shared" / "reference") / "g1"
)
DEFAULT_OUT = REPO_ROOT / "data" / "robots" / "g1_29dof" / "g1_29dof.urdf"
REFERENCE_URDF = "g1_29dof_rev_1_0.urdf"

# Primitive sizes are this fraction of the mesh's extent, so that neighbouring
# links' primitives do not overlap grossly (the meshes themselves interpenetrate
# around the joints).
SHRINK = 0.9

# Shape kind per link, keyed by the link name without its "left_"/"right_"
# prefix. "foot" is a box with SHRINK = 1 plus the reference's sole spheres.
# Every link with a mesh must be listed here, so that a changed reference is
# noticed instead of silently getting a default shape.
SHAPE_KIND = {
    # Trunk.
    "pelvis": "box",
    "pelvis_contour_link": "box",
    "waist_yaw_link": "box",
    "waist_roll_link": "box",
    "torso_link": "box",
    "logo_link": "box",
    "head_link": "box",
    # Legs: blocks at the hip and ankle, capsules along thigh and shin.
    "hip_pitch_link": "box",
    "hip_roll_link": "capsule",
    "hip_yaw_link": "capsule",  # the thigh
    "knee_link": "capsule",  # the shin
    "ankle_pitch_link": "box",
    "ankle_roll_link": "foot",
    # Arms: a block at the shoulder, capsules along upper arm and forearm,
    # small boxes for the wrist links and the hand.
    "shoulder_pitch_link": "box",
    "shoulder_roll_link": "capsule",
    "shoulder_yaw_link": "capsule",
    "elbow_link": "capsule",  # the forearm
    "wrist_roll_link": "box",
    "wrist_pitch_link": "box",
    "wrist_yaw_link": "box",
    "rubber_hand": "box",
}

# Sole spheres expected on each foot in the reference.
SOLE_COUNT = 4
SOLE_RADIUS = 0.005

HEADER = """\
<!--
  Unitree G1, 29 DoF (rev 1.0), for ThorArena.

  Generated by tools/make_g1_urdf.py from the Unitree G1 29-DoF rev 1.0 description
  (g1_29dof_rev_1_0.urdf; BSD-3-Clause, Unitree Robotics; see LICENSE.unitree).
  Numbers (kinematics, inertials, joint limits) are unchanged from the reference;
  the meshes are replaced by collision primitives fitted to them, and visuals are
  dropped. Collisions named "sole" are the reference's foot spheres.
  Capsules lie along the local z axis of their origin; length = distance between
  the hemisphere centres.

  Do not edit by hand: change and re-run tools/make_g1_urdf.py instead.
-->
"""


class InputError(Exception):
    """The reference description is missing or not what this script expects."""


def required_child(elem: ET.Element, path: str, context: str) -> ET.Element:
    """``elem.find(path)``, which the reference must have (`context` names `elem`)."""
    found = elem.find(path)
    if found is None:
        raise InputError(f"{context}: <{elem.tag}> has no <{path}>")
    return found


def required_attr(elem: ET.Element, key: str, context: str) -> str:
    """``elem.get(key)``, which the reference must have (`context` names `elem`)."""
    value = elem.get(key)
    if value is None:
        raise InputError(f"{context}: <{elem.tag}> has no {key!r} attribute")
    return value


def element_name(elem: ET.Element) -> str:
    """The ``name`` attribute of a <link> or <joint>, which the reference must have."""
    return required_attr(elem, "name", "reference URDF")


# ---------------------------------------------------------------------------
# Reading
# ---------------------------------------------------------------------------


def read_stl(path: Path) -> np.ndarray:
    """Return the triangles of a binary or ASCII STL file as an (n, 3, 3) array."""
    data = path.read_bytes()
    # Binary STL: 80-byte header, uint32 count, 50 bytes per triangle. Some
    # binary files start their header with "solid", so decide by the size.
    if len(data) >= 84:
        (count,) = struct.unpack_from("<I", data, 80)
        if len(data) == 84 + 50 * count:
            record = np.dtype([("normal", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])
            tris = np.frombuffer(data, dtype=record, count=count, offset=84)["v"]
            return tris.astype(np.float64)
    # ASCII STL: "vertex x y z" lines, three per facet.
    verts = [
        [float(x) for x in line.split()[1:4]]
        for line in data.decode("ascii", errors="replace").splitlines()
        if line.strip().startswith("vertex")
    ]
    if not verts or len(verts) % 3:
        raise InputError(f"{path}: not a readable STL file")
    return np.asarray(verts, dtype=np.float64).reshape(-1, 3, 3)


def link_mesh(link: ET.Element) -> str | None:
    """The mesh file name of a link (from its visual), after checking that every
    mesh geometry of the link is that file, at the link origin, unscaled."""
    names: set[str] = set()
    for geom_parent in link.findall("visual") + link.findall("collision"):
        mesh = geom_parent.find("geometry/mesh")
        if mesh is None:
            continue
        origin = geom_parent.find("origin")
        if origin is not None:
            xyz = [float(v) for v in origin.get("xyz", "0 0 0").split()]
            rpy = [float(v) for v in origin.get("rpy", "0 0 0").split()]
            if any(xyz) or any(rpy):
                raise InputError(f"link {link.get('name')}: mesh origin is not zero")
        if mesh.get("scale") is not None:
            raise InputError(f"link {link.get('name')}: scaled meshes are not supported")
        names.add(required_attr(mesh, "filename", f"link {link.get('name')}"))
    if len(names) > 1:
        raise InputError(f"link {link.get('name')}: several different meshes {sorted(names)}")
    return names.pop() if names else None


# ---------------------------------------------------------------------------
# Fitting
# ---------------------------------------------------------------------------


@dataclass
class Primitive:
    """A collision primitive in the link frame."""

    kind: str  # "box", "capsule" or "sphere"
    xyz: tuple[float, float, float]
    rpy: tuple[float, float, float]
    # box: (sx, sy, sz); capsule: (radius, length); sphere: (radius,)
    dims: tuple[float, ...]


def fit_box(tris: np.ndarray, shrink: float) -> Primitive:
    """Link-frame axis-aligned box around the mesh, scaled by `shrink` about its centre."""
    verts = tris.reshape(-1, 3)
    lo, hi = verts.min(axis=0), verts.max(axis=0)
    return Primitive("box", tuple((lo + hi) / 2), (0.0, 0.0, 0.0), tuple((hi - lo) * shrink))


def fit_foot_box(tris: np.ndarray, sole_z: float) -> Primitive:
    """Unshrunk link-frame box around the foot mesh, but with its bottom raised
    to the bottom of the sole spheres (`sole_z`): the rubber sole of the mesh
    reaches 0.4 mm lower, and a foot box below the spheres would take their
    ground contacts over when full contacts are enabled. The size is rounded
    first so that the written box bottom is the sole bottom to within rounding."""
    verts = tris.reshape(-1, 3)
    lo, hi = verts.min(axis=0), verts.max(axis=0)
    lo[2] = max(lo[2], sole_z)
    size = np.round(hi - lo, 4)
    centre = lo + size / 2.0
    centre[:2] = (lo[:2] + hi[:2]) / 2.0
    return Primitive("box", tuple(centre), (0.0, 0.0, 0.0), tuple(size))


def principal_axes(tris: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean and principal axes (columns, largest variance first) of the mesh
    surface, from the area-weighted covariance of the triangle centroids."""
    centroids = tris.mean(axis=1)
    areas = 0.5 * np.linalg.norm(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]), axis=1)
    weights = areas / areas.sum()
    mean = weights @ centroids
    centred = centroids - mean
    cov = (centred * weights[:, None]).T @ centred
    _, vecs = np.linalg.eigh(cov)  # ascending eigenvalues
    axes = vecs[:, ::-1].copy()
    # Eigenvectors have an arbitrary sign: make each one's largest component
    # positive so the output does not depend on the LAPACK build.
    for i in range(3):
        if axes[np.argmax(np.abs(axes[:, i])), i] < 0:
            axes[:, i] = -axes[:, i]
    return mean, axes


def rpy_from_z_axis(axis: np.ndarray) -> tuple[float, float, float]:
    """URDF rpy (R = Rz(yaw) Ry(pitch) Rx(roll)) turning +z onto the unit `axis`.
    With roll = 0, R z = (cos yaw sin pitch, sin yaw sin pitch, cos pitch)."""
    x, y, z = axis
    pitch = math.acos(max(-1.0, min(1.0, z)))
    yaw = math.atan2(y, x) if math.hypot(x, y) > 1e-12 else 0.0
    return (0.0, pitch, yaw)


def fit_capsule(tris: np.ndarray, shrink: float) -> Primitive:
    """Capsule along the mesh's principal axis, fitted to the vertices' bounding
    box in the principal frame (see the module docstring)."""
    mean, axes = principal_axes(tris)
    local = (tris.reshape(-1, 3) - mean) @ axes  # coordinates in the principal frame
    lo, hi = local.min(axis=0), local.max(axis=0)
    extent = hi - lo
    radius = shrink * (extent[1] + extent[2]) / 4.0
    length = shrink * extent[0] - 2.0 * radius  # between the hemisphere centres
    centre = mean + axes @ ((lo + hi) / 2.0)
    if length <= 0.0:  # stubby mesh: a capsule would be a sphere anyway
        return Primitive("sphere", tuple(centre), (0.0, 0.0, 0.0), (radius,))
    return Primitive("capsule", tuple(centre), rpy_from_z_axis(axes[:, 0]), (radius, length))


# ---------------------------------------------------------------------------
# Writing
# ---------------------------------------------------------------------------


def num(value: float) -> str:
    """A number rounded to 4 decimals, without trailing zeros or "-0"."""
    text = f"{round(value, 4):.4f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def nums(values: Iterable[float]) -> str:
    return " ".join(num(v) for v in values)


def attrs(pairs: Iterable[tuple[str, str | None]]) -> str:
    """XML attribute text from (name, value) pairs, skipping None values."""
    return "".join(
        f' {name}="{value.replace("&", "&amp;").replace(chr(34), "&quot;").replace("<", "&lt;")}"'
        for name, value in pairs
        if value is not None
    )


def copy_tag(elem: ET.Element | None, order: list[str], indent: str) -> list[str]:
    """Emit `elem` (an empty element) with its attribute strings copied verbatim,
    in the given attribute order. Unknown attributes are an error, so nothing
    the reference says is dropped silently."""
    if elem is None:
        return []
    unknown = set(elem.attrib) - set(order)
    if unknown or len(elem):
        raise InputError(f"<{elem.tag}>: unexpected attributes/children {sorted(unknown)}")
    return [f"{indent}<{elem.tag}{attrs((k, elem.get(k)) for k in order)}/>"]


def primitive_xml(prim: Primitive, name: str, indent: str) -> list[str]:
    if prim.kind == "box":
        geom = f'<box size="{nums(prim.dims)}"/>'
    elif prim.kind == "capsule":
        geom = f'<capsule radius="{num(prim.dims[0])}" length="{num(prim.dims[1])}"/>'
    else:
        geom = f'<sphere radius="{num(prim.dims[0])}"/>'
    return [
        f'{indent}<collision name="{name}">',
        f'{indent}  <origin xyz="{nums(prim.xyz)}" rpy="{nums(prim.rpy)}"/>',
        f"{indent}  <geometry>{geom}</geometry>",
        f"{indent}</collision>",
    ]


def sole_radius(sole: ET.Element, context: str) -> str:
    """The radius attribute of a sole sphere <collision>, verbatim."""
    return required_attr(required_child(sole, "geometry/sphere", context), "radius", context)


def sole_spheres(link: ET.Element) -> list[ET.Element]:
    """The reference's sole spheres of a foot link, checked."""
    context = f"link {link.get('name')}"
    soles = [c for c in link.findall("collision") if c.find("geometry/sphere") is not None]
    radii = {float(sole_radius(c, context)) for c in soles}
    if len(soles) != SOLE_COUNT or radii != {SOLE_RADIUS}:
        raise InputError(
            f"link {link.get('name')}: expected {SOLE_COUNT} sole spheres of radius "
            f"{SOLE_RADIUS}, found {len(soles)} with radii {sorted(radii)}"
        )
    return soles


def sole_bottom(link: ET.Element) -> float:
    """Lowest z (link frame) of the foot's sole spheres."""
    context = f"link {link.get('name')}"
    return min(
        float(required_attr(required_child(s, "origin", context), "xyz", context).split()[2])
        - float(sole_radius(s, context))
        for s in sole_spheres(link)
    )


def link_xml(link: ET.Element, reference: Path) -> tuple[list[str], str]:
    """The output lines of one link and its one-line summary."""
    name = element_name(link)
    out = [f'  <link name="{name}">']
    inertial = link.find("inertial")
    if inertial is not None:
        out.append("    <inertial>")
        out += copy_tag(inertial.find("origin"), ["xyz", "rpy"], "      ")
        out += copy_tag(inertial.find("mass"), ["value"], "      ")
        out += copy_tag(
            inertial.find("inertia"), ["ixx", "ixy", "ixz", "iyy", "iyz", "izz"], "      "
        )
        out.append("    </inertial>")

    mesh = link_mesh(link)
    if mesh is None:
        summary = "no mesh, no collision"
    else:
        base = name.removeprefix("left_").removeprefix("right_")
        if base not in SHAPE_KIND:
            raise InputError(f"link {name}: no shape kind chosen in SHAPE_KIND")
        kind = SHAPE_KIND[base]
        mesh_path = reference / mesh
        if not mesh_path.is_file():
            raise InputError(f"mesh not found: {mesh_path}")
        tris = read_stl(mesh_path)
        if kind == "foot":
            for sole in sole_spheres(link):
                out.append('    <collision name="sole">')
                out += copy_tag(sole.find("origin"), ["xyz", "rpy"], "      ")
                radius = sole_radius(sole, f"link {name}")
                out.append(f'      <geometry><sphere radius="{radius}"/></geometry>')
                out.append("    </collision>")
            prim = fit_foot_box(tris, sole_bottom(link))
            out += primitive_xml(prim, "foot", "    ")
            summary = f"{SOLE_COUNT} x sole sphere r {SOLE_RADIUS} + foot "
        else:
            prim = fit_box(tris, SHRINK) if kind == "box" else fit_capsule(tris, SHRINK)
            out += primitive_xml(prim, prim.kind, "    ")
            summary = ""
        if prim.kind == "box":
            summary += f"box size {nums(prim.dims)}"
        elif prim.kind == "capsule":
            summary += f"capsule r {num(prim.dims[0])} length {num(prim.dims[1])}"
        else:
            summary += f"sphere r {num(prim.dims[0])}"
        summary += f" at xyz {nums(prim.xyz)}"
        if any(prim.rpy):
            summary += f" rpy {nums(prim.rpy)}"
    out.append("  </link>")
    return out, summary


def joint_xml(joint: ET.Element) -> list[str]:
    """The output lines of one joint, numbers copied verbatim."""
    kind = joint.get("type")
    if kind not in ("revolute", "fixed"):
        raise InputError(f"joint {joint.get('name')}: unexpected type {kind!r}")
    out = [f'  <joint name="{joint.get("name")}" type="{kind}">']
    out += copy_tag(joint.find("origin"), ["xyz", "rpy"], "    ")
    out += copy_tag(joint.find("parent"), ["link"], "    ")
    out += copy_tag(joint.find("child"), ["link"], "    ")
    out += copy_tag(joint.find("axis"), ["xyz"], "    ")
    out += copy_tag(joint.find("limit"), ["lower", "upper", "effort", "velocity"], "    ")
    out.append("  </joint>")
    return out


def generate(reference: Path) -> tuple[str, list[tuple[str, str]]]:
    """The output URDF text and the per-link summaries."""
    urdf_path = reference / REFERENCE_URDF
    if not urdf_path.is_file():
        raise InputError(
            f"reference URDF not found: {urdf_path}\n"
            "  (expected Unitree's G1 29-DoF rev 1.0 description; pass --reference DIR)"
        )
    root = ET.parse(urdf_path).getroot()
    lines = [
        '<?xml version="1.0" encoding="utf-8"?>',
        HEADER.rstrip("\n"),
        f'<robot name="{root.get("name")}">',
    ]
    summaries: list[tuple[str, str]] = []
    # Keep the reference's document order of links and joints; drop everything
    # else (the <mujoco> block; comments are not parsed).
    for elem in root:
        if elem.tag == "link":
            link_lines, summary = link_xml(elem, reference)
            lines += link_lines
            summaries.append((element_name(elem), summary))
        elif elem.tag == "joint":
            lines += joint_xml(elem)
        elif elem.tag != "mujoco":
            raise InputError(f"unexpected top-level element <{elem.tag}>")
    lines.append("</robot>")
    return "\n".join(lines) + "\n", summaries


# ---------------------------------------------------------------------------
# Verification
# ---------------------------------------------------------------------------


def verify(reference_urdf: Path, out_text: str) -> list[str]:
    """Compare the written URDF with the reference; return the problems found."""
    ref = ET.parse(reference_urdf).getroot()
    new = ET.fromstring(out_text)
    problems: list[str] = []

    def by_name(root: ET.Element, tag: str) -> dict[str | None, ET.Element]:
        return {e.get("name"): e for e in root.findall(tag)}

    def attrib(e: ET.Element | None) -> dict[str, str] | None:
        return None if e is None else dict(e.attrib)

    ref_links, new_links = by_name(ref, "link"), by_name(new, "link")
    ref_joints, new_joints = by_name(ref, "joint"), by_name(new, "joint")
    if list(ref_links) != list(new_links):
        problems.append("link names or order differ")
    if list(ref_joints) != list(new_joints):
        problems.append("joint names or order differ")
    for name, rj in ref_joints.items():
        nj = new_joints.get(name)
        if nj is None:
            continue
        for path in ("origin", "parent", "child", "axis", "limit"):
            if attrib(rj.find(path)) != attrib(nj.find(path)):
                problems.append(f"joint {name}: <{path}> differs")
        if rj.get("type") != nj.get("type"):
            problems.append(f"joint {name}: type differs")
    for name, rl in ref_links.items():
        nl = new_links.get(name)
        if nl is None:
            continue
        for path in ("inertial/origin", "inertial/mass", "inertial/inertia"):
            if attrib(rl.find(path)) != attrib(nl.find(path)):
                problems.append(f"link {name}: <{path}> differs")
        if nl.find("visual") is not None or nl.find(".//mesh") is not None:
            problems.append(f"link {name}: has a visual or a mesh")
        for c in nl.findall("collision"):
            geometry = c.find("geometry")
            shapes = [] if geometry is None else [g.tag for g in geometry]
            if len(shapes) != 1 or shapes[0] not in ("box", "sphere", "capsule", "cylinder"):
                problems.append(f"link {name}: collision geometry {shapes}")
            elif c.get("name") not in ("sole", "foot", shapes[0]):
                problems.append(f"link {name}: collision name {c.get('name')!r}")
    if new.find("mujoco") is not None:
        problems.append("<mujoco> element present")
    return problems


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--reference",
        type=Path,
        default=DEFAULT_REFERENCE,
        help=f"Unitree G1 description directory holding {REFERENCE_URDF} and meshes/ "
        "(default: ../shared/reference/g1 next to the repository)",
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=DEFAULT_OUT,
        help="output URDF (default: data/robots/g1_29dof/g1_29dof.urdf in the repository)",
    )
    args = parser.parse_args()

    try:
        text, summaries = generate(args.reference)
    except (InputError, OSError, ET.ParseError) as err:
        print(f"make_g1_urdf: error: {err}", file=sys.stderr)
        return 1

    width = max(len(name) for name, _ in summaries)
    for name, summary in summaries:
        print(f"{name:<{width}}  {summary}")

    problems = verify(args.reference / REFERENCE_URDF, text)
    if problems:
        for p in problems:
            print(f"make_g1_urdf: verification failed: {p}", file=sys.stderr)
        return 1

    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_bytes(text.encode("utf-8"))
    root = ET.fromstring(text)
    print(
        f"wrote {args.out} ({len(root.findall('link'))} links, "
        f"{len(root.findall('joint'))} joints, {len(root.findall('link/collision'))} collisions); "
        "numbers verified against the reference"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
