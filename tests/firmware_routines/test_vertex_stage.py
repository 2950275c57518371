"""The vertex stage keeps only what every triangle looks up (render.inc VTX_*: outcode, screen
position, z / w, 1 / w); the clip-space and world-space positions are computed again when a
triangle is cut or lit flat (vertex.S vertex_clip, face_world). Those must be the values the
vertex stage itself used, bit for bit, or a clipped triangle's cut corners would not meet its
neighbours' and flat lighting would differ from the reference. Driven on the board model's CPU
through tests/support/firmware_calls.py: vertex_setup and vertex_range on a generated mesh, then each
vertex asked again. When both harts draw, each fills its share of the vertex stage
(render.S render_vertex_share): the shares together must fill what one pass fills."""
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
    """Where vertex_range keeps world positions (vertex_world_array; vertex_init sets it for
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
    assert fw.call("vertex_setup", [frame]).a[0] == records_at
    fw.call("vertex_range", [0, VERTICES])

    out_clip = fw.symbol("OUT_NEAR") | fw.symbol("OUT_GUARD")
    offsets = {name: fw.symbol(name) for name in ("VTX_OUTCODE", "VTX_SX", "VTX_SY", "VTX_ZW", "VTX_Q", "VTX_SNAP_X")}
    # the records as float32 depth keeps them (the snap's residual where int16 keeps z / w)...
    fw.write(fw.symbol("vertex_snap_kept"), struct.pack("<Q", 1))
    fw.call("vertex_range", [0, VERTICES])
    residual_records = fw.read(records_at, VERTICES * vtx_bytes)
    # ...and as int16 depth (and wireframe) does
    fw.write(fw.symbol("vertex_snap_kept"), struct.pack("<Q", 0))
    fw.call("vertex_range", [0, VERTICES])
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
            # project_clip's position before snapping, in pixels from the screen's centre (within
            # float32 rounding of x / w * 160 and -y / w * 120), and with float32 depth the record's
            # snap residual: that position less the snapped one, to the nearest 2^-15 pixel, at most
            # 1/32 pixel (half a Q4 step)
            fx, fy = np.float32(projected.fa(2)), np.float32(projected.fa(3))
            assert abs(fx - x / w * 160) <= 1e-5 * max(1.0, abs(fx)) and abs(fy + y / w * 120) <= 1e-5 * max(1.0, abs(fy))
            other = residual_records[index * vtx_bytes:(index + 1) * vtx_bytes]
            assert other[:offsets["VTX_ZW"]] == record[:offsets["VTX_ZW"]], f"vertex {index}"
            rx, ry = struct.unpack_from("<hh", other, offsets["VTX_SNAP_X"])
            for residual, exact, snapped in ((rx, fx, (sx - 160 * 16) / 16), (ry, fy, (sy - 120 * 16) / 16)):
                assert abs(residual) <= 2 ** 15 / 32 + 1, f"vertex {index}"
                assert abs(residual / 2 ** 15 - (float(exact) - snapped)) <= 2 ** -16 + 1e-4 * abs(snapped) * 2 ** -10, \
                    f"vertex {index}"
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



POISON_BYTE = 0xA5          # what the arrays hold before the vertex stage fills them
GUARD = 64                  # bytes after each array that no share may write


def set_gouraud(fw: FirmwareCaller, normals: np.ndarray, normals_at: int, light_at: int) -> None:
    """shading = gouraud as render_init leaves it: the RASTER_GOURAUD fill, the mesh's normals,
    where their intensities go, the light, the ambient and 65 light levels."""
    scene = fw.symbol("scene")
    fw.write(scene + fw.symbol("MESH_NCOUNT"), struct.pack("<I", len(normals)))
    fw.write(scene + fw.symbol("MESH_N"), struct.pack("<Q", normals_at))
    fw.write_f32(normals_at, normals.reshape(-1))
    fw.write_f32(scene + fw.symbol("SCENE_LIGHT"), [0.36, 0.48, 0.8])
    fw.write_f32(scene + fw.symbol("SCENE_AMBIENT"), [0.2])
    fw.write(fw.symbol("render_fill"), struct.pack("<I", fw.symbol("RASTER_GOURAUD")))
    fw.write(fw.symbol("normal_light"), struct.pack("<Q", light_at))
    fw.write_f32(fw.symbol("light_quantum"), [64.0, 1.0])       # 65 levels: LIGHT_ONE / 64 a level


@pytest.mark.parametrize("vertices, normals", [(401, 57), (64, 64), (3, 0), (2, 3), (1, 1), (0, 0)])
def test_the_vertex_stage_in_two_shares_fills_what_one_pass_fills(fw, vertices, normals):
    """render_vertex_share (main.S: hart 0 runs share 0, hart 1 share 1 when both draw): the two
    shares fill every vertex record, flat shading's world position and Gouraud's normal
    intensity once, bit for bit as the whole stage in one share does, in either order, and
    nothing past the arrays, whatever the counts (odd, fewer than the shares, none)."""
    rng = np.random.default_rng(vertices)
    # mostly in view, the last two behind the near plane and beyond the guard band (outcode only)
    positions = rng.uniform(-1.5, 1.5, (vertices, 3)).astype(np.float32)
    positions[max(0, vertices - 2):] = np.array([[0, 0, 3.5], [400, -400, 0]], np.float32)[:min(2, vertices)]
    unit = rng.normal(size=(normals, 3))
    unit = (unit / np.linalg.norm(unit, axis=1, keepdims=True)).astype(np.float32)
    vtx_bytes, world_bytes = fw.symbol("VTX_BYTES"), fw.symbol("WORLD_POS_BYTES")
    mesh_at = fw.scratch
    normals_at = mesh_at + positions.nbytes + GUARD
    arrays = {"records": (normals_at + unit.nbytes + GUARD, vertices * vtx_bytes)}
    arrays["world"] = (arrays["records"][0] + arrays["records"][1] + GUARD, vertices * world_bytes)
    arrays["light"] = (arrays["world"][0] + arrays["world"][1] + GUARD, normals * fw.symbol("NORMAL_LIGHT_BYTES"))
    set_scene(fw, positions, mesh_at, arrays["records"][0])
    world_array(fw, arrays["world"][0])
    set_gouraud(fw, unit, normals_at, arrays["light"][0])
    fw.call("vertex_setup", [5])

    def fill(shares: list[tuple[int, int]]) -> dict[str, bytes]:
        """The arrays (and the guard after each) after the given render_vertex_share calls."""
        for at, size in arrays.values():
            fw.write(at, bytes([POISON_BYTE]) * (size + GUARD))
        for share, count in shares:
            fw.call("render_vertex_share", [share, count])
        return {name: fw.read(at, size + GUARD) for name, (at, size) in arrays.items()}

    one = fill([(0, 1)])
    assert fill([(0, 2), (1, 2)]) == one
    assert fill([(1, 2), (0, 2)]) == one
    untouched = bytes([POISON_BYTE]) * GUARD
    assert all(one[name][-GUARD:] == untouched for name in arrays), "a share wrote past its array"
    records = one["records"]
    outcode = fw.symbol("VTX_OUTCODE")
    assert all(records[i * vtx_bytes + outcode:i * vtx_bytes + outcode + 4] != untouched[:4]
               for i in range(vertices)), "a vertex record was left unfilled"
    assert untouched[:4] not in [one["world"][i:i + 4] for i in range(0, vertices * world_bytes, 4)]
    assert untouched[:4] not in [one["light"][i:i + 4] for i in range(0, arrays["light"][1], 4)]

