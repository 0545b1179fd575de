"""SRDF files (MoveIt's semantic robot description): the collision pairs to leave out, groups,
end effectors; and writing the pairs found by `armkit.planning.disabled_pairs`.

An SRDF names links and joints of a URDF. What armkit reads from it:

- ``<disable_collisions link1="..." link2="..." reason="..."/>``: link pairs never tested for
  self-collision (`armkit.planning.ArmGeometry.with_disabled`), with MoveIt's reasons
  (Adjacent, Default, Never, Always, User);
- ``<group>``: its joints, links, chains (base and tip links) and subgroups, by name; a chain's
  tip is the tip a URDF's arm is read to (`SRDF.tip`);
- ``<end_effector>``: name, parent link, group.

Everything else (group states, virtual joints, passive joints) is ignored. The file is parsed as
the URDF reader parses: at most `MAX_SRDF_BYTES`, no entity declarations, every required name
present; a mistake is one `ModelFileError` naming the file and the element.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from xml.sax.saxutils import quoteattr

from armkit.errors import ModelFileError
from armkit.io.documents import found_text, read_bytes
from armkit.io.urdf import robot_element

MAX_SRDF_BYTES = 8 * 2**20
"""The largest SRDF file read (bytes); a humanoid's is about 200 kB."""


@dataclass(frozen=True)
class SRDFGroup:
    """A planning group of an SRDF: its joints and links, chains ``(base, tip)`` and the
    groups it includes, by name."""

    name: str
    joints: tuple[str, ...] = ()
    links: tuple[str, ...] = ()
    chains: tuple[tuple[str, str], ...] = ()
    groups: tuple[str, ...] = ()


@dataclass(frozen=True)
class SRDF:
    """What armkit reads from an SRDF file.

    Attributes
    ----------
    path : str
    robot : str
        The robot's name.
    disabled : tuple of (str, str, str)
        ``(link1, link2, reason)`` of each ``<disable_collisions>``, in file order.
    groups : dict of str to SRDFGroup
    end_effectors : tuple of (str, str, str)
        ``(name, parent_link, group)``.
    """

    path: str
    robot: str
    disabled: tuple[tuple[str, str, str], ...] = ()
    groups: dict = field(default_factory=dict)
    end_effectors: tuple[tuple[str, str, str], ...] = ()

    @property
    def disabled_pairs(self) -> tuple[tuple[str, str], ...]:
        """The link pairs never tested, without their reasons."""
        return tuple((a, b) for a, b, _ in self.disabled)

    def tip(self, group: str) -> str | None:
        """The tip link of a group's (first) chain, following included groups; None if it
        has no chain."""
        seen: set[str] = set()
        todo = [group]
        while todo:
            name = todo.pop(0)
            if name in seen or name not in self.groups:
                continue
            seen.add(name)
            g = self.groups[name]
            if g.chains:
                return g.chains[0][1]
            todo.extend(g.groups)
        return None


def _name(element: ET.Element, attribute: str, path: str, where: str) -> str:
    value = element.get(attribute)
    if not value or not value.strip():
        raise ModelFileError(path, f"{where} {attribute}", "a name",
                             "none" if value is None else found_text(value))
    return value


def read_srdf(path: str | Path, links=None) -> SRDF:
    """Read an SRDF file.

    Parameters
    ----------
    path : str or Path
    links : collection of str, optional
        The URDF's link names: a ``<disable_collisions>`` naming another link is refused.

    Raises
    ------
    ModelFileError
        The file is not XML, its root is not ``<robot>``, an element lacks a required name,
        or a pair names a link that `links` does not hold.
    """
    path = str(path)
    root = robot_element(path, read_bytes(path, MAX_SRDF_BYTES), "SRDF")
    known = None if links is None else set(links)
    disabled = []
    for k, element in enumerate(root.findall("disable_collisions")):
        where = f"<disable_collisions>[{k}]"
        a, b = _name(element, "link1", path, where), _name(element, "link2", path, where)
        if known is not None:
            for attribute, name in (("link1", a), ("link2", b)):
                if name not in known:
                    raise ModelFileError(path, f"{where} {attribute}", "a link of the URDF",
                                         found_text(name))
        disabled.append((a, b, element.get("reason", "")))
    groups = {}
    for k, element in enumerate(root.findall("group")):
        where = f"<group>[{k}]"
        name = _name(element, "name", path, where)
        groups[name] = SRDFGroup(
            name,
            tuple(_name(j, "name", path, f"group {name} <joint>")
                  for j in element.findall("joint")),
            tuple(_name(x, "name", path, f"group {name} <link>") for x in element.findall("link")),
            tuple((_name(c, "base_link", path, f"group {name} <chain>"),
                   _name(c, "tip_link", path, f"group {name} <chain>"))
                  for c in element.findall("chain")),
            tuple(_name(g, "name", path, f"group {name} <group>")
                  for g in element.findall("group")))
    end_effectors = tuple(
        (_name(e, "name", path, f"<end_effector>[{k}]"),
         _name(e, "parent_link", path, f"<end_effector>[{k}]"), e.get("group", ""))
        for k, e in enumerate(root.findall("end_effector")))
    return SRDF(path, root.get("name", ""), tuple(disabled), groups, end_effectors)


def write_srdf(path: str | Path, robot: str, disabled) -> None:
    """Write an SRDF holding the ``<disable_collisions>`` pairs `disabled`: ``(link1, link2,
    reason)`` each, as `armkit.planning.disabled_pairs` gives them (MoveIt and `read_srdf` read
    it back)."""
    lines = ['<?xml version="1.0"?>', f"<robot name={quoteattr(str(robot))}>"]
    for a, b, reason in disabled:
        lines.append(f"  <disable_collisions link1={quoteattr(str(a))} "
                     f"link2={quoteattr(str(b))} reason={quoteattr(str(reason))}/>")
    lines.append("</robot>")
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")
