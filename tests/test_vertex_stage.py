"""The vertex stage keeps only what every triangle looks up (render.inc VTX_*: outcode, screen
position, z / w, 1 / w); the clip-space and world-space positions are computed again when a
triangle is cut or lit flat (vertex.S vertex_clip, face_world). Those must be the values the
vertex stage itself used, bit for bit, or a clipped triangle's cut corners would not meet its
neighbours' and flat lighting would differ from the reference. Driven on the board model's CPU
through tests/firmware_calls.py: vertex_transform on a generated mesh, then each vertex asked
again."""
from __future__ import annotations

import struct

import numpy as np
import pytest

from firmware_calls import FirmwareCaller, bits_f32

VERTICES = 400


@pytest.fixture(scope="module")
def fw(firmware) -> FirmwareCaller:
    return FirmwareCaller(firmware)


def set_scene(fw: FirmwareCaller, positions: np.ndarray, mesh_at: int, records_at: int) -> None:
    """A scene as scene.S leaves it (every field the vertex stage reads) around `positions`."""
    scene = fw.symbol("scene")
    fw.write(scene, bytes(fw.symbol("SCENE_SIZE")))
    fw.write_f32(scene + fw.symbol("SCENE_SCALE"), [1.5, 0.75, 1.25])
    fw.write_f32(scene + fw.symbol("SCENE_AXIS"), [0.36, 0.48, 0.8])
    fw.write_f32(scene + fw.symbol("SCENE_ANGLE"), [37.0, 4.0])      # angle, step
    fw.write_f32(scene + fw.symbol("SCENE_TRANSLATE"), [0.25, -0.5, -3.0])
    fw.write_f32(scene + fw.symbol("SCENE_FOV"), [60.0, 0.5, 40.0])  # fov, near, far
    fw.write(scene + fw.symbol("MESH_VCOUNT"), struct.pack("<I", len(positions)))
    fw.write(scene + fw.symbol("MESH_V"), struct.pack("<Q", mesh_at))
    fw.write_f32(mesh_at, positions.reshape(-1))
    fw.write(fw.symbol("vertex_records"), struct.pack("<Q", records_at))


def world_array(fw: FirmwareCaller, address: int) -> None:
    """Where vertex_transform keeps world positions (vertex_world_array; vertex_init sets it for
    flat shading), or 0 for none."""
    fw.write(fw.symbol("vertex_world_array"), struct.pack("<Q", address))


def test_vertex_clip_and_world_give_the_vertex_stage_values(fw):
    """For vertices inside, beyond the guard band and behind the near plane: vertex_clip's
    position has the record's outcode and projects (project_clip) to the record's screen
    position, depth and 1 / w exactly; face_world gives each corner of a triangle the model
    matrix applied to it (fused multiply-adds in float32, checked against float64 to the
    rounding of the last bits), bit for bit what the vertex stage keeps in vertex_world_array
    for flat shading."""
    rng = np.random.default_rng(11)
    positions = np.concatenate([rng.uniform(-1.5, 1.5, (VERTICES - 40, 3)),
                                rng.uniform(-400, 400, (20, 3)),                      # guard band
                                rng.uniform(-1, 1, (20, 3)) + [0, 0, 3.5]]).astype(np.float32)
    vtx_bytes = fw.symbol("VTX_BYTES")
    mesh_at = fw.scratch
    records_at = mesh_at + positions.nbytes + 64
    world_at = records_at + VERTICES * vtx_bytes + 64
    out_at = world_at + VERTICES * fw.symbol("WORLD_POS_BYTES") + 64
    set_scene(fw, positions, mesh_at, records_at)
    world_array(fw, world_at)
    frame = 3
    assert fw.call("vertex_transform", [frame]).a[0] == records_at

    out_clip = fw.symbol("OUT_NEAR") | fw.symbol("OUT_GUARD")
    offsets = {name: fw.symbol(name) for name in ("VTX_OUTCODE", "VTX_SX", "VTX_SY", "VTX_ZW", "VTX_Q")}
    model = fw.read_f32(fw.symbol("vertex_model"), 12).astype(np.float64).reshape(3, 4)
    kinds = set()
    for index in range(VERTICES):
        record = fw.read(records_at + index * vtx_bytes, vtx_bytes)
        outcode, sx, sy = struct.unpack_from("<Iii", record, offsets["VTX_OUTCODE"])
        fw.call("vertex_clip", [index, out_at])
        clip = fw.read_f32(out_at, 4)
        x, y, z, w = (float(v) for v in clip)
        g = float(bits_f32(fw.symbol("F32_GUARD_BAND")))
        expected = ((x < -w) | (x > w) << 1 | (y < -w) << 2 | (y > w) << 3 | (z < 0) << 4
                    | (z > w) << 5 | (float(np.float32(g) * np.float32(w)) < max(abs(x), abs(y))) << 6)
        assert outcode == expected, f"vertex {index}: outcode {outcode:#x}, from vertex_clip {expected:#x}"
        kinds.add(outcode & out_clip)
        if not outcode & out_clip:
            projected = fw.call("project_clip", fargs=[float(v) for v in clip])
            assert (projected.a_signed(0, 32), projected.a_signed(1, 32)) == (sx, sy), f"vertex {index}"
            zw_q = struct.unpack_from("<II", record, offsets["VTX_ZW"])
            assert (int(np.float32(projected.fa(0)).view(np.uint32)),
                    int(np.float32(projected.fa(1)).view(np.uint32))) == zw_q, f"vertex {index}"
    # face_world on triangles of packed corners (scene.inc MESH_F: v in the low bits, vt and vn
    # above it, here all ones, as for a corner without them)
    no_index = fw.symbol("MESH_NO_INDEX")
    t_shift, n_shift = fw.symbol("MESH_CORNER_T_SHIFT"), fw.symbol("MESH_CORNER_N_SHIFT")
    triangle_at = out_at + 256
    for first in range(0, VERTICES - 2, 7):
        corners = (first, VERTICES - 1 - first, (first * 31) % VERTICES)
        fw.write(triangle_at, struct.pack("<3Q", *(v | no_index << t_shift | no_index << n_shift for v in corners)))
        fw.call("face_world", [triangle_at, out_at])
        computed = fw.read(out_at, 36)
        kept = b"".join(fw.read(world_at + 12 * v, 12) for v in corners)
        assert computed == kept, f"triangle {corners}: face_world differs from vertex_world_array"
        world = fw.read_f32(out_at, 9).astype(np.float64).reshape(3, 3)
        exact = positions[list(corners)].astype(np.float64) @ model[:, :3].T + model[:, 3]
        assert np.allclose(world, exact, rtol=4e-7, atol=1e-6), f"triangle {corners}: {world} != {exact}"
    near, guard = fw.symbol("OUT_NEAR"), fw.symbol("OUT_GUARD")
    assert 0 in kinds and any(k & near for k in kinds) and any(k & guard for k in kinds), \
        f"the mesh should have vertices inside, behind the near plane and beyond the guard band: {kinds}"

