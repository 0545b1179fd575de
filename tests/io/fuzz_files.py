"""Mutated robot files (YAML) and URDFs, from a seeded generator, loaded under a time guard.

Each mutated file has a class that says what loading it must do:

- ``refuse``: invalid by construction (a bool in a number field, a loop, 1e308 m, ...): an
  ArmkitError whose message starts with the file's path and names the field (when the
  mutation knows it); loading it is a silently accepted invalid file.
- ``same``: a change that keeps the model (keys reordered, comments, a mimic finger off the
  chain, meshes): it must load, to the same forward kinematics as the file it came from.
- ``either``: random damage (bytes flipped, cut, repeated; a value of another type): an
  ArmkitError naming the file, or a model whose forward kinematics are finite.

Loads run in one worker process that the runner restarts after a hang (no answer within
`timeout` s), so a hang is counted, not suffered. Any other exception type is a failure.

Run more than the test suite does::

    python -m tests.io.fuzz_files --count 2000 --seed 14
"""

from __future__ import annotations

import argparse
import copy
import json
import os
import random
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
from collections import Counter
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import yaml

# --- the cases ------------------------------------------------------------------------------


@dataclass
class Case:
    """One mutated file: its path, how to load it, what it must give."""

    kind: str                     # "yaml" or "urdf"
    path: str
    expect: str                   # "refuse", "same" or "either"
    mutation: str
    field: str = ""               # a text the refusal must contain (the field or element)
    tip: str | None = None        # URDF: the chain's tip
    reference: str | None = None  # "same": the file it must equal
    reference_tip: str | None = None
    also: str | None = None       # another file a refusal may name (a wrapped URDF)


TREE = """<robot name="tree">
  <link name="base"/><link name="l1"/><link name="l2"/><link name="l3"/><link name="hand"/>
  <link name="camera"/>
  <joint name="yaw" type="continuous"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.3"/><axis xyz="0 0 1"/><limit velocity="2" effort="5"/></joint>
  <joint name="slide" type="prismatic"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.1 0 0" rpy="0 0 0"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.5" velocity="0.2" effort="10"/></joint>
  <joint name="pitch" type="revolute"><parent link="l2"/><child link="l3"/>
    <origin xyz="0.2 0 0.05" rpy="0.1 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-1.5" upper="1.5" velocity="1" effort="10"/></joint>
  <joint name="hand_mount" type="fixed"><parent link="l3"/><child link="hand"/>
    <origin xyz="0.05 0 0" rpy="0 1.5707963 0"/></joint>
  <joint name="camera_mount" type="fixed"><parent link="l1"/><child link="camera"/>
    <origin xyz="0 0 0.1"/></joint>
</robot>
"""

# A robot file that wraps a URDF (wrapped_tree.urdf, written beside it).
WRAPPER = """name: wrapped
units: {length: mm, angle: deg}
convention: urdf
urdf: wrapped_tree.urdf
tip: hand
base: {xyz: [0, 0, 100], rpy: [0, 0, 90]}
tool: {xyz: [0, 0, 20], rpy: [0, 0, 0]}
"""

# Real files from the example-robot-data wheel (the test extra), with the chain to load.
REAL_URDFS = [("ur_description/urdf/ur5_robot.urdf", "tool0"),
              ("panda_description/urdf/panda.urdf", "panda_hand"),
              ("so_arm_description/urdf/so101.urdf", "gripper_frame_link"),
              ("kinova_description/robots/kinova.urdf", "j2s6s200_end_effector")]

BAD_NUMBERS = ["nan", "inf", "-inf", "1e308", "-1e309", "\u0661", "\u0664.5", "1_0", "0x10",
               "", "1 2", "one", "1e", "--1", "1.2.3", "\uff11"]
ANY_VALUES = [None, True, False, 0, -1, 1e-300, 1e300, -1e300, 10**400, "x", "", [], {},
              [1, 2, 3], [[1]], {"a": 1}, "dh", "revolute", 0.5, 360, -360, 1e6]


def real_urdf(suffix: str) -> Path:
    """An installed example-robot-data file whose path ends with `suffix`."""
    import importlib.metadata
    dist = importlib.metadata.distribution("example-robot-data")
    found = [f for f in dist.files or () if str(f).replace("\\", "/").endswith(suffix)]
    if len(found) != 1:
        raise FileNotFoundError(f"example-robot-data: {len(found)} files end with {suffix}")
    return Path(dist.locate_file(found[0]))


def builtin_yaml() -> dict[str, str]:
    folder = resources.files("armkit.model") / "robots"
    return {p.name: p.read_text(encoding="utf-8") for p in folder.iterdir()
            if p.name.endswith(".yaml")}


# --- robot file (YAML) mutations ------------------------------------------------------------

def _paths(node, prefix=()):
    """Every (path, value) leaf of a parsed document; paths are tuples of keys and indices."""
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _paths(v, prefix + (i,))
    yield prefix, node


def _field(path) -> str:
    """The field path as messages write it, without trailing list indices (``joints[1].a``)."""
    path = list(path)
    while path and isinstance(path[-1], int):
        path.pop()
    out = ""
    for part in path:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out


def _set(doc, path, value):
    node = doc
    for part in path[:-1]:
        node = node[part]
    node[path[-1]] = value


def _numbers(doc):
    return [p for p, v in _paths(doc) if p and isinstance(v, (int, float))
            and not isinstance(v, bool)]


def _dump(doc, rng) -> str:
    return yaml.safe_dump(doc, sort_keys=False, default_flow_style=rng.choice([None, False]))


def yaml_refuse(rng: random.Random, doc: dict, text: str) -> tuple[str, str, str]:
    """(mutation, file text, field) for a robot document made invalid."""
    doc = copy.deepcopy(doc)
    joints = doc.get("joints", [])
    choice = rng.randrange(22)
    if choice == 0:
        path = rng.choice(_numbers(doc))
        _set(doc, path, rng.choice([True, False]))
        return "bool for a number", _dump(doc, rng), _field(path)
    if choice == 1:
        path = rng.choice(_numbers(doc))
        _set(doc, path, str(rng.choice([1.5, 0, 300, -2.5])))
        return "string for a number", _dump(doc, rng), _field(path)
    if choice == 2:
        path = rng.choice(_numbers(doc))
        _set(doc, path, rng.choice([1e308, -1e308, 1e200, -5e10, 3e12, 10**400, -(10**30)]))
        return "huge number", _dump(doc, rng), _field(path)
    if choice == 3:
        path = rng.choice(_numbers(doc))
        _set(doc, path, rng.choice([float("nan"), float("inf"), -float("inf")]))
        return "non-finite number", _dump(doc, rng), _field(path)
    if choice == 4:
        path = rng.choice(_numbers(doc))
        _set(doc, path, [0.0] if rng.random() < 0.5 else {"value": 1})
        return "container for a number", _dump(doc, rng), _field(path)
    if choice == 5 and len(joints) >= 2:
        i, j = rng.sample(range(len(joints)), 2)
        name = joints[i].get("name") or "dup"
        joints[i]["name"] = joints[j]["name"] = name
        return "duplicate joint name", _dump(doc, rng), f"joints[{max(i, j)}].name"
    if choice == 6:
        doc["convention"] = rng.choice([["dh"], {"dh": 1}, 5, True, None, "DH", "screw", ""])
        return "bad convention", _dump(doc, rng), "convention"
    if choice == 7:
        required = [("name",), ("units",), ("convention",),
                    ("joints",) if "joints" in doc else ("urdf",)]
        required += [("units", "length"), ("units", "angle")]
        if doc.get("convention") == "poe":
            required.append(("home",))
        for i, joint in enumerate(joints):
            keys = ["type"] + (["alpha", "a", "d", "theta"] if "alpha" in joint else ["axis"])
            if joint.get("type") == "prismatic":
                keys.append("limits")
            if joint.get("type") == "revolute" and "point" in joint:
                keys.append("point")
            required += [("joints", i, k) for k in keys]
        path = rng.choice(required)
        node = doc
        for part in path[:-1]:
            node = node[part]
        del node[path[-1]]
        return "required field removed", _dump(doc, rng), ""
    if choice == 8:
        target = rng.choice([doc] + joints + ([doc["units"]] if "units" in doc else []))
        target[rng.choice(["colour", "lenght", "limts", "Name", "jionts"])] = 1
        return "unknown field", _dump(doc, rng), "unknown field"
    if choice == 9:
        limited = [i for i, j in enumerate(joints) if "limits" in j]
        if limited:
            i = rng.choice(limited)
            lo, hi = joints[i]["limits"]
            joints[i]["limits"] = rng.choice([[hi, lo], [lo, lo], [lo], [lo, hi, hi], []])
            return "bad limits", _dump(doc, rng), f"joints[{i}].limits"
    if choice == 10 and joints:
        i = rng.randrange(len(joints))
        joints[i]["type"] = rng.choice(["spherical", "Revolute", "", 1, True, None, ["revolute"]])
        return "bad joint type", _dump(doc, rng), f"joints[{i}]"
    if choice == 11:
        doc["units"] = rng.choice([{"length": "inch", "angle": "deg"}, {"length": "mm"},
                                   "mm", [], {"length": "m", "angle": "grad"}])
        return "bad units", _dump(doc, rng), "units"
    if choice == 12 and joints:
        doc["joints"] = rng.choice([[], 3, "joints", {"a": 1}, [1, 2], [None]])
        return "bad joint list", _dump(doc, rng), "joints"
    if choice == 13 and joints:
        i = rng.randrange(len(joints))
        key = rng.choice(["velocity", "acceleration"])
        if joints[i].get("type") != "fixed":
            joints[i][key] = rng.choice([0, -1, -0.5, 1e300])
            return "bad rate limit", _dump(doc, rng), f"joints[{i}].{key}"
    # Text-level mutations: YAML the parser itself must refuse.
    if choice == 14:
        bomb = ['lol0: &a0 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
        bomb += [f"lol{k}: &a{k} [" + ", ".join([f"*a{k - 1}"] * 8) + "]" for k in range(1, 9)]
        return "alias bomb", text + "\n".join(bomb) + "\n", "alias"
    if choice == 15:
        depth = rng.choice([65, 200, 900, 5000])
        nest = rng.choice([("[" * depth, "]" * depth), ("{a: " * depth, "}" * depth)])
        return "deep nesting", text + f"deep: {nest[0]}1{nest[1]}\n", "nesting deeper"
    if choice == 16:
        key = rng.choice(["name", "units", "convention"])
        return "duplicate key", text + f"{key}: again\n", "given twice"
    if choice == 17:
        return "empty file", rng.choice(["", "\n", "# nothing\n", "---\n", "...\n", "~\n"]), ""
    if choice == 18:
        return "huge integer literal", text + "big: " + "7" * rng.choice([4301, 10**5]) + "\n", ""
    if choice == 19:
        return "bad date", text + "when: 2001-02-30\n", ""
    if choice == 20:
        return "python tag", text + "x: !!python/object/apply:os.system [ls]\n", ""
    if choice == 21:
        return "alias reuse", text.replace("units:", "units: &u", 1) + "other: *u\n", "alias"
    return yaml_refuse(rng, doc, text)           # that mutation did not apply here


def yaml_same(rng: random.Random, doc: dict, text: str) -> tuple[str, str]:
    """(mutation, text) for a document that must give the same robot."""
    choice = rng.randrange(4)
    if choice == 0:
        keys = list(doc)
        rng.shuffle(keys)
        return "keys reordered", _dump({k: doc[k] for k in keys}, rng)
    if choice == 1:
        out = []
        for line in text.splitlines():
            # Whole-line comments before top-level keys, end-of-line ones after flow
            # collections: never inside a block scalar, where a # is text.
            if line[:1].isalpha() and rng.random() < 0.3:
                out.append("# " + "x" * rng.randrange(80))
            if line.rstrip().endswith(("}", "]")) and rng.random() < 0.3:
                line += "   # a comment: with [brackets] & *stars"
            out.append(line)
        return "comments added", "\n".join(out) + "\n"
    if choice == 2:
        doc = copy.deepcopy(doc)
        for path in _numbers(doc):
            node = doc
            for part in path[:-1]:
                node = node[part]
            if isinstance(node[path[-1]], int):      # 90 -> 90.0: the same value
                node[path[-1]] = float(node[path[-1]])
        return "ints written as floats", _dump(doc, rng)
    return "flow style", yaml.safe_dump(doc, sort_keys=False, default_flow_style=True)


def yaml_either(rng: random.Random, doc: dict, text: str) -> tuple[str, str]:
    if rng.random() < 0.5:
        doc = copy.deepcopy(doc)
        for _ in range(rng.randint(1, 3)):
            paths = [p for p, _ in _paths(doc) if p]
            _set(doc, rng.choice(paths), copy.deepcopy(rng.choice(ANY_VALUES)))
        return "values replaced", _dump(doc, rng)
    return "bytes damaged", _damage(rng, text)


def _damage(rng: random.Random, text: str) -> str:
    data = bytearray(text.encode("utf-8"))
    for _ in range(rng.randint(1, 4)):
        if not data:
            break
        i = rng.randrange(len(data))
        op = rng.randrange(5)
        if op == 0:
            data[i] = rng.choice(b"0123456789-+.eE:[]{},&*!|>'\"#\n \t\x00\xff")
        elif op == 1:
            del data[i:i + rng.randint(1, 20)]
        elif op == 2:
            data[i:i] = data[i:i + rng.randint(1, 40)]
        elif op == 3:
            del data[i:]
        else:
            data[i:i] = rng.choice(["\u0661".encode(), b"1e308", b"true", b".nan", b"*a", b"&a ",
                                    b"\xc3", b"!!binary ", b"<<: "])
    return data.decode("utf-8", errors="surrogateescape")   # written back byte for byte


# --- URDF mutations -------------------------------------------------------------------------

def _urdf_info(root: ET.Element, tip: str):
    """The chain's joints (tip first) of a parsed URDF: a list of <joint> elements."""
    by_child = {j.find("child").get("link"): j for j in root.findall("joint")}
    chain, link = [], tip
    while link in by_child:
        chain.append(by_child[link])
        link = by_child[link].find("parent").get("link")
    return chain


def _xml(root: ET.Element) -> str:
    return ET.tostring(root, encoding="unicode")


def urdf_refuse(rng: random.Random, text: str, tip: str) -> tuple[str, str, str]:
    root = ET.fromstring(text)
    chain = _urdf_info(root, tip)
    moving = [j for j in chain if j.get("type") != "fixed"]
    joints = root.findall("joint")
    links = root.findall("link")
    choice = rng.randrange(16)
    if choice == 0:
        joint = rng.choice(chain)
        origin = joint.find("origin")
        if origin is None:
            origin = ET.SubElement(joint, "origin")
        attribute = rng.choice(["xyz", "rpy"])
        values = (origin.get(attribute) or "0 0 0").split()
        values[rng.randrange(3)] = rng.choice(BAD_NUMBERS)
        origin.set(attribute, " ".join(values) if rng.random() < 0.8 else "1 2")
        return "bad origin number", _xml(root), f"joint '{joint.get('name')}' <origin>"
    if choice == 1:
        joint = rng.choice(moving)
        axis = joint.find("axis")
        if axis is None:
            axis = ET.SubElement(joint, "axis", xyz="1 0 0")
        bad = rng.choice(BAD_NUMBERS + ["0 0 0", "1e308 0 0", "0 0 0.0", "1 1 1 1"])
        axis.set("xyz", bad if " " in bad else f"0 {bad} 1")
        return "bad axis", _xml(root), f"joint '{joint.get('name')}' <axis>"
    if choice == 2:
        joint = rng.choice(moving)
        limit = joint.find("limit")
        if limit is None:
            limit = ET.SubElement(joint, "limit", lower="-1", upper="1")
        limit.set("velocity", rng.choice(BAD_NUMBERS + ["0", "-1", "0.0", "-0", "1e300"]))
        return "bad velocity", _xml(root), f"joint '{joint.get('name')}' <limit>"
    if choice == 3:
        limited = [j for j in moving if j.get("type") in ("revolute", "prismatic")]
        if limited:
            joint = rng.choice(limited)
            limit = joint.find("limit")
            lower, upper = limit.get("lower"), limit.get("upper")
            swap = rng.randrange(4)
            if swap == 0:
                limit.set("lower", upper)
                limit.set("upper", lower)
            elif swap == 1:
                limit.set("upper", lower)
            elif swap == 2:
                limit.set(rng.choice(["lower", "upper"]), rng.choice(BAD_NUMBERS))
            else:
                del limit.attrib[rng.choice(["lower", "upper"])]
            return "bad position limits", _xml(root), f"joint '{joint.get('name')}' <limit>"
    if choice == 4 and len(joints) >= 2:
        a, b = rng.sample(joints, 2)
        a.set("name", b.get("name"))
        return "duplicate joint name", _xml(root), f"joint '{b.get('name')}'"
    if choice == 5:
        name = rng.choice(links).get("name")
        root.append(ET.Element("link", name=name))
        return "duplicate link name", _xml(root), f"link '{name}'"
    if choice == 6:
        joint = rng.choice(joints)
        child = joint.find("child").get("link")
        extra = ET.SubElement(root, "joint", name="extra_joint", type="fixed")
        ET.SubElement(extra, "parent", link=links[0].get("name")
                      if links[0].get("name") != child else links[1].get("name"))
        ET.SubElement(extra, "child", link=child)
        return "link with two parents", _xml(root), f"link '{child}'"
    if choice == 7 and len(chain) >= 2:
        k = rng.randrange(1, len(chain))          # chain[0] is the tip's joint
        lower = rng.choice(chain[:k])              # a joint below chain[k]
        chain[k].find("parent").set("link", lower.find("child").get("link"))
        return "loop", _xml(root), "loop"
    if choice == 8:
        joint = rng.choice(joints)
        joint.find(rng.choice(["parent", "child"])).set("link", "ghost_link")
        return "undeclared link", _xml(root), "'ghost_link', which no <link> declares"
    if choice == 9:
        used = {j.find("child").get("link") for j in joints}
        link = rng.choice([x for x in links if x.get("name") in used])
        root.remove(link)
        return "link removed", _xml(root), "which no <link> declares"
    if choice == 10:
        joint = rng.choice(joints)
        joint.set("type", rng.choice(["spherical", "Revolute", "", "ball", "screw"]))
        return "unknown joint type", _xml(root), f"joint '{joint.get('name')}' type"
    if choice == 11 and moving:
        # A mimic joint on the chain is a model of its own; one that follows no moving joint
        # of the file (a fixed one, or none) is invalid.
        joint = rng.choice(moving)
        fixed = [j.get("name") for j in joints if j.get("type") == "fixed"]
        ET.SubElement(joint, "mimic", joint=rng.choice(fixed + ["ghost_joint"]), multiplier="1")
        return "mimic of no moving joint", _xml(root), f"joint '{joint.get('name')}' <mimic>"
    if choice == 12:
        joint = rng.choice(chain)
        joint.set("type", rng.choice(["floating", "planar"]))
        return "floating joint on the chain", _xml(root), f"joint '{joint.get('name')}' type"
    if choice == 13:
        return ("entity declaration", '<!DOCTYPE r [<!ENTITY a "aaaaaaaa"><!ENTITY b "&a;&a;&a;'
                '&a;&a;">]>\n' + _xml(root).replace("<robot", "<robot x='&b;'", 1), "ENTITY")
    if choice == 14:
        cut = _xml(root)
        return "truncated XML", cut[:rng.randrange(1, len(cut) - 1)], "XML"
    if choice == 15:
        root.tag = rng.choice(["sdf", "Robot", "model"])
        return "not a robot element", _xml(root), "<robot> root element"
    return urdf_refuse(rng, text, tip)


def urdf_same(rng: random.Random, text: str, tip: str) -> tuple[str, str]:
    root = ET.fromstring(text)
    choice = rng.randrange(4)
    if choice == 0:
        children = list(root)
        rng.shuffle(children)
        for child in list(root):
            root.remove(child)
        root.extend(children)
        return "elements reordered", _xml(root)
    chain_links = {j.find("child").get("link") for j in _urdf_info(root, tip)}
    off = [link.get("name") for link in root.findall("link")
           if link.get("name") not in chain_links]
    anchor = rng.choice(off or [root.findall("link")[0].get("name")])
    if choice == 1:       # a mimic finger with velocity="0", as real grippers have
        ET.SubElement(root, "link", name="fuzz_finger")
        finger = ET.SubElement(root, "joint", name="fuzz_finger_joint", type="prismatic")
        ET.SubElement(finger, "parent", link=anchor)
        ET.SubElement(finger, "child", link="fuzz_finger")
        ET.SubElement(finger, "limit", lower="0", upper="0.04", velocity="0", effort="0")
        ET.SubElement(finger, "mimic", joint=root.findall("joint")[0].get("name"),
                      multiplier="-1", offset="0.01")
        return "mimic joint off the chain", _xml(root)
    if choice == 2:       # a floating body hanging off the tree
        ET.SubElement(root, "link", name="fuzz_float")
        free = ET.SubElement(root, "joint", name="fuzz_free", type="floating")
        ET.SubElement(free, "parent", link=anchor)
        ET.SubElement(free, "child", link="fuzz_float")
        return "floating joint off the chain", _xml(root)
    for link in root.findall("link"):   # meshes by package:// paths that do not exist
        visual = ET.SubElement(link, "visual")
        geometry = ET.SubElement(visual, "geometry")
        ET.SubElement(geometry, "mesh", filename=f"package://nowhere/{link.get('name')}.stl")
    return "package:// meshes", _xml(root)


def urdf_either(rng: random.Random, text: str, tip: str) -> tuple[str, str]:
    if rng.random() < 0.5:
        root = ET.fromstring(text)
        elements = [e for e in root.iter() if e.attrib]
        for _ in range(rng.randint(1, 3)):
            element = rng.choice(elements)
            attribute = rng.choice(list(element.attrib))
            element.set(attribute, rng.choice(BAD_NUMBERS + ["0", "1", "-1", "0.5 0.5 0.5",
                                                            "0 0 1", "fixed", "base", tip]))
        return "attributes replaced", _xml(root)
    return "bytes damaged", _damage(rng, text)


# --- generation -----------------------------------------------------------------------------

def generate(kind: str, count: int, seed: int, folder: Path) -> list[Case]:
    """`count` mutated files of `kind` ("yaml" or "urdf") written into `folder`."""
    rng = random.Random(f"{seed}-{kind}")
    cases: list[Case] = []
    if kind == "yaml":
        bases = []
        for name, text in sorted(builtin_yaml().items()):
            path = folder / f"base_{name}"
            path.write_text(text, encoding="utf-8")
            bases.append((path, yaml.safe_load(text), text))
        (folder / "wrapped_tree.urdf").write_text(TREE, encoding="utf-8")
        text = WRAPPER
        path = folder / "base_wrapper.yaml"
        path.write_text(text, encoding="utf-8")
        bases.append((path, yaml.safe_load(text), text))
    else:
        bases = []
        sources = [("tree.urdf", TREE, "hand")] + [
            (Path(s).name, real_urdf(s).read_text(encoding="utf-8"), tip) for s, tip in REAL_URDFS]
        for name, text, tip in sources:
            path = folder / f"base_{name}"
            path.write_text(text, encoding="utf-8")
            bases.append((path, tip, text))
    for i in range(count):
        base = bases[i % len(bases)]
        roll = rng.random()
        expect = "refuse" if roll < 0.5 else ("same" if roll < 0.65 else "either")
        suffix = ".yaml" if kind == "yaml" else ".urdf"
        path = folder / f"{kind}_{i:05d}{suffix}"
        if kind == "yaml":
            base_path, doc, text = base
            if expect == "refuse":
                mutation, new, field_ = yaml_refuse(rng, doc, text)
            elif expect == "same":
                (mutation, new), field_ = yaml_same(rng, doc, text), ""
            else:
                (mutation, new), field_ = yaml_either(rng, doc, text), ""
            case = Case(kind, str(path), expect, mutation, field_, None, str(base_path),
                        also=str(folder / "wrapped_tree.urdf"))
        else:
            base_path, tip, text = base
            if expect == "refuse":
                mutation, new, field_ = urdf_refuse(rng, text, tip)
            elif expect == "same":
                (mutation, new), field_ = urdf_same(rng, text, tip), ""
            else:
                (mutation, new), field_ = urdf_either(rng, text, tip), ""
            case = Case(kind, str(path), expect, mutation, field_, tip, str(base_path), tip)
        path.write_text(new, encoding="utf-8", errors="surrogateescape")
        cases.append(case)
    return cases


# --- the worker: loads one file per request -------------------------------------------------

def _load(case: dict):
    import armkit
    from armkit.io.urdf import read_urdf
    from armkit.model import chain_from_urdf
    if case["kind"] == "urdf":
        table = read_urdf(case["path"], tip=case["tip"])
        return armkit.Robot("fuzz", chain_from_urdf(table))
    return armkit.load_robot(case["path"])


def _check(case: dict) -> dict:
    """Load one case; say what happened (never raise)."""
    import numpy as np

    import armkit
    start = time.perf_counter()
    try:
        robot = _load(case)
    except armkit.ArmkitError as err:
        return {"outcome": "refused", "message": str(err)[:1000],
                "seconds": time.perf_counter() - start}
    except BaseException as err:                  # noqa: BLE001 - the failure being counted
        return {"outcome": "crashed", "message": f"{type(err).__name__}: {str(err)[:300]}",
                "seconds": time.perf_counter() - start}
    seconds = time.perf_counter() - start
    try:
        lower, upper = robot.chain.sampling_limits
        Q = np.random.default_rng(0).uniform(lower, upper, (16, robot.n))
        poses = armkit.fk(robot, Q)
        finite = bool(np.isfinite(poses).all()) and bool(np.isfinite(lower).all())
        same = None
        if case["expect"] == "same":
            reference = _load({**case, "path": case["reference"], "tip": case["reference_tip"]})
            same = (reference.n == robot.n
                    and reference.joint_names == robot.joint_names
                    and np.array_equal(armkit.fk(reference, Q), poses)
                    and np.array_equal(reference.lower, robot.lower)
                    and np.array_equal(reference.upper, robot.upper)
                    and np.array_equal(reference.chain.velocity_limits,
                                       robot.chain.velocity_limits))
    except BaseException as err:                  # noqa: BLE001
        return {"outcome": "crashed", "message": f"after loading: {type(err).__name__}: "
                f"{str(err)[:300]}", "seconds": seconds}
    return {"outcome": "loaded", "finite": finite, "same": same, "n": robot.n,
            "seconds": seconds}


def serve() -> None:
    """Answer one JSON case per stdin line with one JSON result line on stdout."""
    for line in sys.stdin:
        result = _check(json.loads(line))
        sys.stdout.write(json.dumps(result) + "\n")
        sys.stdout.flush()


# --- the runner -----------------------------------------------------------------------------

@dataclass
class Report:
    counts: Counter = field(default_factory=Counter)   # (kind, expect, outcome) -> files
    failures: list = field(default_factory=list)
    slowest: float = 0.0

    def lines(self) -> list[str]:
        out = []
        for kind in ("yaml", "urdf"):
            total = sum(v for k, v in self.counts.items() if k[0] == kind)
            if not total:
                continue
            parts = ", ".join(f"{e} -> {o}: {v}" for (k, e, o), v in sorted(self.counts.items())
                              if k == kind)
            out.append(f"{kind}: {total} files; {parts}")
        out.append(f"failures: {len(self.failures)}; slowest load {self.slowest:.3f} s")
        return out


class Worker:
    """A child process running `module`'s `serve` (this module's by default), restarted after
    a hang."""

    def __init__(self, module: str = "tests.io.fuzz_files"):
        self.process = None
        self.module = module

    def start(self):
        root = str(Path(__file__).resolve().parents[2])
        env = {**os.environ, "PYTHONPATH": os.pathsep.join(
            [p for p in (os.environ.get("PYTHONPATH"), root) if p])}
        self.process = subprocess.Popen(
            [sys.executable, "-c", f"from {self.module} import serve; serve()"],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
            text=True, env=env, cwd=root)

    def ask(self, case: Case, timeout: float) -> dict | None:
        """The worker's answer, or None if it gave none within `timeout` s (then restarted)."""
        import selectors
        if self.process is None or self.process.poll() is not None:
            self.start()
        self.process.stdin.write(json.dumps(case.__dict__) + "\n")
        self.process.stdin.flush()
        with selectors.DefaultSelector() as selector:
            selector.register(self.process.stdout, selectors.EVENT_READ)
            ready = selector.select(timeout)
        line = self.process.stdout.readline() if ready else ""
        if not line:
            self.stop()
            return None
        return json.loads(line)

    def stop(self):
        if self.process is not None:
            self.process.kill()
            self.process.wait()
            self.process = None


def judge(case: Case, result: dict | None) -> str | None:
    """Why this result breaks the rules for this case, or None if it keeps them."""
    if result is None:
        return "no answer in time (a hang)"
    if result["outcome"] == "crashed":
        return f"not an ArmkitError: {result['message']}"
    if result["outcome"] == "refused":
        message = result["message"]
        if not (message.startswith(case.path) or case.also and message.startswith(case.also)):
            return f"refusal does not name the file: {message}"
        if "\n" in message:
            return f"refusal is not one line: {message!r}"
        if case.expect == "same":
            return f"a file with the same model was refused: {message}"
        if case.field and case.field not in message:
            return f"refusal does not name {case.field!r}: {message}"
        return None
    if case.expect == "refuse":
        return "an invalid file was accepted"
    if not result["finite"]:
        return "loaded, but forward kinematics or limits are not finite"
    if case.expect == "same" and not result["same"]:
        return "loaded to a different model"
    return None


def run(count: int, seed: int, kinds=("yaml", "urdf"), timeout: float = 60.0,
        folder: Path | None = None) -> Report:
    """Generate and load `count` mutated files of each kind; the report of what happened."""
    report = Report()
    worker = Worker()
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(folder or scratch)
        try:
            for kind in kinds:
                for case in generate(kind, count, seed, folder):
                    result = worker.ask(case, timeout)
                    outcome = "hang" if result is None else result["outcome"]
                    report.counts[(kind, case.expect, outcome)] += 1
                    if result is not None:
                        report.slowest = max(report.slowest, result["seconds"])
                    why = judge(case, result)
                    if why:
                        report.failures.append(f"{case.mutation} ({Path(case.path).name}): {why}")
        finally:
            worker.stop()
    return report


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=2000, help="files of each kind")
    parser.add_argument("--seed", type=int, default=14)
    parser.add_argument("--kind", choices=["yaml", "urdf"], action="append")
    parser.add_argument("--keep", type=Path, help="write the files here and keep them")
    args = parser.parse_args(argv)
    if args.keep:
        args.keep.mkdir(parents=True, exist_ok=True)
    start = time.monotonic()
    report = run(args.count, args.seed, tuple(args.kind or ("yaml", "urdf")), folder=args.keep)
    print(f"seed {args.seed}, {args.count} files of each kind, {time.monotonic() - start:.0f} s")
    print("\n".join(report.lines()))
    for failure in report.failures[:50]:
        print("  FAIL", failure)
    return 1 if report.failures else 0


if __name__ == "__main__":
    sys.exit(main())
