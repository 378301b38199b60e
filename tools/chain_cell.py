#!/usr/bin/env python3
"""Writes an MJCF cell with an N-joint serial chain robot (for timing the safety stage against the
joint count). The chain stands on a fixed base, hinges alternate about z and y, the links share
1.6 m; a wall stands beside it. Keyframes: `a` (straight up) and `b` (every y hinge bent a little
toward the wall). Usage: chain_cell.py N [WALL_X] > cell.xml (WALL_X: the wall's centre [m], default 0.9)"""
import sys


def chain_cell(n, total=1.6, wall_x=0.9):
    seg = total / n
    body = []
    indent = "    "
    for i in range(n):
        axis = "0 0 1" if i % 2 == 0 else "0 1 0"
        pos = "0 0 0.2" if i == 0 else f"0 0 {seg:.6g}"
        body.append(f'{indent}<body name="l{i + 1}" pos="{pos}">')
        body.append(f'{indent}  <joint name="j{i + 1}" type="hinge" axis="{axis}" range="-3 3" user="1.5"/>')
        body.append(f'{indent}  <geom name="g{i + 1}" type="box" size="0.03 0.03 {0.4 * seg:.6g}" '
                    f'pos="0 0 {0.5 * seg:.6g}" contype="1" conaffinity="0"/>')
        indent += "  "
    body.append(f'{indent}<site name="tool0" pos="0 0 {seg:.6g}"/>')
    for i in reversed(range(n)):
        indent = indent[:-2]
        body.append(f"{indent}</body>")
    bend = [0.0 if i % 2 == 0 else 0.6 / (n // 2) for i in range(n)]
    return "\n".join([
        f'<mujoco model="chain{n}">',
        '  <compiler angle="radian" autolimits="true"/>',
        "  <worldbody>",
        '    <geom name="floor" type="plane" size="5 5 0.1" contype="0" conaffinity="0"/>',
        '    <body name="base">',
        '      <geom name="base_box" type="box" size="0.1 0.1 0.1" pos="0 0 0.1" contype="1" conaffinity="0"/>',
        *["  " + line for line in body],
        "    </body>",
        f'    <geom name="wall" type="box" size="0.05 1 1" pos="{wall_x:g} 0 1" contype="0" conaffinity="1"/>',
        "  </worldbody>",
        "  <keyframe>",
        f'    <key name="a" qpos="{" ".join("0" for _ in range(n))}"/>',
        f'    <key name="b" qpos="{" ".join(f"{v:.6g}" for v in bend)}"/>',
        "  </keyframe>",
        "</mujoco>",
        "",
    ])


if __name__ == "__main__":
    sys.stdout.write(chain_cell(int(sys.argv[1]), wall_x=float(sys.argv[2]) if len(sys.argv) > 2 else 0.9))
