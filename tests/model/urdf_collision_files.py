"""A small hand-written URDF with collision primitives, shared by the reader and geometry tests.

Chain base -> j1 -> l1 -> j2 -> l2 -> (fixed) tool; a sensor hangs on l1 through a fixed joint
turned 90 deg about z; a finger slides off the chain (prismatic joint, not part of the arm).
"""

from __future__ import annotations

ARM = """<robot name="hand">
  <link name="base">
    <collision><origin xyz="0 0 0.05"/><geometry><sphere radius="0.1"/></geometry></collision>
  </link>
  <link name="l1">
    <visual><geometry><mesh filename="package://nowhere/l1.stl"/></geometry></visual>
    <collision><origin xyz="0.2 0 0" rpy="0 1.5707963267948966 0"/>
      <geometry><cylinder radius="0.05" length="0.4"/></geometry></collision>
  </link>
  <link name="sensor">
    <collision><origin xyz="0 0.1 0"/><geometry><box size="0.1 0.3 0.02"/></geometry></collision>
  </link>
  <link name="l2">
    <collision><origin xyz="0.1 0 0"/><geometry><sphere radius="0.03"/></geometry></collision>
  </link>
  <link name="tool">
    <collision><geometry><cylinder radius="0.02" length="0.06"/></geometry></collision>
  </link>
  <link name="finger">
    <collision><geometry><box size="0.01 0.01 0.05"/></geometry></collision>
  </link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.2"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="10" velocity="1"/></joint>
  <joint name="mount" type="fixed"><parent link="l1"/><child link="sensor"/>
    <origin xyz="0.4 0 0" rpy="0 0 1.5707963267948966"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.5 0 0"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="10" velocity="1"/></joint>
  <joint name="tool_mount" type="fixed"><parent link="l2"/><child link="tool"/>
    <origin xyz="0.15 0 0"/></joint>
  <joint name="grip" type="prismatic"><parent link="l2"/><child link="finger"/>
    <origin xyz="0.1 0.05 0"/><axis xyz="0 1 0"/><limit lower="0" upper="0.04" effort="10" velocity="1"/></joint>
</robot>"""

TIP = "tool"
