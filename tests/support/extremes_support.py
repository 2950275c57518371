"""Helpers of tests/slow/test_extremes.py: running one adversarial scene on the board model, comparing
its frames with the float64 reference renderer within named tolerances, and the firmware's heap
budget read from its ELF (so that the memory-limit cases follow the heap layout when it changes).

Tolerances used by the comparisons (each one is the documented place where the firmware is not
exact, reference/render.py's module docstring):

- lighting: the firmware quantises the intensity I to k = round(64 I) (light_levels = 65, the
  default) and rounds each RGB565 channel c to floor((c k + 32) / 64) (render.S shade_rgb565,
  raster.S FILL with LIGHT_ROUND_SPREAD); the reference rounds c I. Both round to nearest, so what
  is left is k's quantisation: |c k / 64 - c I| <= c / 128 < 1/2, and the firmware's channel is
  the reference's, one more or one less, never anything else (`lighting_ok`). In RGB888 as the
  LCD shows it that is up to 9 (a 5-bit step).
- outline: the firmware snaps screen positions to 1/16 pixel (Q4); a pixel centre within about
  1/16 pixel of an edge can fall on the other side. Such pixels lie on the outline of what the
  reference drew (a pixel whose 3x3 neighbourhood holds more than one reference colour).
"""
from __future__ import annotations

import contextlib
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from PIL import Image

import reference
import reference.render as reference_render
from suite import make_card, run_emulator
from firmware_calls import elf_symbols
from k210_common.exit_status import EXIT_FIRMWARE_ERROR
from k210_common.firmware_errors import firmware_error

TEXTURE_1X1 = b"P6\n1 1\n255\n\x80\x40\x20"


# --------------------------------------------------------------------------- runs

@dataclass
class Run:
    returncode: int
    out: Path
    card: Path
    stderr: str
    frames: list[np.ndarray] = field(default_factory=list)

    @property
    def console(self) -> str:
        log = self.out / "console.log"
        return log.read_text() if log.exists() else ""

    def error_line(self) -> str | None:
        found = re.search(r"^error \d+ .*$", self.console, re.M)
        return found.group(0) if found else None

    @property
    def background(self) -> np.ndarray:
        """The scene's background colour as the LCD shows it (RGB888)."""
        scene = reference.load_card_scene(self.card)
        return reference.rgb565_to_rgb888(np.array([scene.background]))[0]

    def compare(self, frame: int, firmware_lighting: bool = False) -> "Comparison":
        return compare(self.frames[frame], self.reference(frame, firmware_lighting), self.background)

    def reference(self, frame: int, firmware_lighting: bool = False) -> np.ndarray:
        """The reference's frame (RGB888), optionally with the firmware's lighting quantisation."""
        scene, mesh, texture = reference.load_card_image(self.card)
        with (firmware_lighting_in_reference() if firmware_lighting else contextlib.nullcontext()):
            return reference.render_image(scene, mesh, texture, frame)


def run_scene(firmware: Path, folder: Path, model: str | bytes, scene: str | None,
              texture: bytes = TEXTURE_1X1, frames: int = 3, timeout: float = 600,
              budget_s: float | None = None) -> Run:
    """Builds a card (model.obj, texture.ppm, scene.ini unless None) and runs it for `frames`, with
    --check-writes: every adversarial case also shows that the firmware stores only inside its own
    buffers (a stray store ends the run with status 10, which no case expects). `budget_s`: the
    board's --budget, for models whose loading alone takes longer than its default 5 virtual
    seconds (the hang detection counts from reset to the first frame)."""
    files = {"/model.obj": model.encode() if isinstance(model, str) else model, "/texture.ppm": texture}
    if scene is not None:
        files["/scene.ini"] = scene.encode()
    card = make_card(folder, files)
    out = folder / "out"
    result = run_emulator("run", str(firmware), "--sd", str(card), "--frames", str(frames), "--out", str(out),
                          "--quiet", "--check-writes",
                          *([] if budget_s is None else ["--budget", str(budget_s)]), timeout=timeout)
    run = Run(result.returncode, out, card, result.stderr)
    if result.returncode == 0:
        run.frames = [np.asarray(Image.open(out / f"frame_{n:04d}.png").convert("RGB")) for n in range(frames)]
    return run


ONE_TRIANGLE = "v 0 0 -1\nv 1 0 -1\nv 0 1 -1\nf 1 2 3\n"
# the firmware's errors these tests meet (firmware/include/errors.inc), and the outcomes
# boot_allocations names them by
BAD_SCENE = firmware_error("BAD_SCENE")
FILE_TOO_LARGE = firmware_error("TOO_LARGE")
MODEL_TOO_LARGE = firmware_error("MODEL_TOO_LARGE")
FILE_TOO_LARGE_OUTCOME = f"error {FILE_TOO_LARGE.code}"
MODEL_TOO_LARGE_OUTCOME = f"error {MODEL_TOO_LARGE.code}"


def check_scene_key_agreement(firmware: Path, folder: Path, key: str, value: str, refusal: str | None) -> None:
    """`key = value` on line 2 of a scene.ini: the card builder's reader (reference/scene.py) and the
    firmware both take it (refusal None), or both refuse it with the same message, the firmware's
    error 9 ending the run with the board's status for a fatal error."""
    from reference.scene import SceneError, parse_scene
    text = f"mode = flat\n{key} = {value}\n"
    try:
        parse_scene(text)
        host = None
    except SceneError as error:
        host = str(error)
    run = run_scene(firmware, folder, ONE_TRIANGLE, text, frames=1)
    if refusal is None:
        assert host is None and run.returncode == 0, (host, run.stderr)
    else:
        assert host == refusal
        assert run.returncode == EXIT_FIRMWARE_ERROR and f"error {BAD_SCENE.code} {host}" in run.console, \
            (run.returncode, run.stderr)


# --------------------------------------------------------------------------- comparisons

def rgb565_channels(image: np.ndarray) -> np.ndarray:
    """(240, 320, 3) RGB888 as the board model shows RGB565 -> the 5/6/5-bit channels (exact
    inverse of the LCD's expansion)."""
    image = np.asarray(image, dtype=np.int64)
    return np.stack([image[..., 0] >> 3, image[..., 1] >> 2, image[..., 2] >> 3], axis=-1)


def outline_mask(ref: np.ndarray) -> np.ndarray:
    """Pixels whose 3x3 neighbourhood in the reference frame holds more than one colour."""
    ref = np.asarray(ref, dtype=np.int64)
    packed = (ref[..., 0] << 16) | (ref[..., 1] << 8) | ref[..., 2]
    padded = np.pad(packed, 1, mode="edge")
    mask = np.zeros(packed.shape, dtype=bool)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            mask |= padded[1 + dy:1 + dy + packed.shape[0], 1 + dx:1 + dx + packed.shape[1]] != packed
    return mask


def within_one_pixel(a: np.ndarray, b: np.ndarray) -> bool:
    """Every pixel set in a has a pixel set in b among its 8 neighbours or itself."""
    padded = np.pad(b, 1)
    near = np.zeros_like(b)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            near |= padded[1 + dy:1 + dy + b.shape[0], 1 + dx:1 + dx + b.shape[1]]
    return not np.any(a & ~near)


@dataclass
class Comparison:
    differing: int              # pixels not bit-identical
    max_error: int              # largest RGB888 channel difference
    beyond_lighting: int        # pixels that differ by more than the lighting quantisation
    beyond_lighting_off_outline: int   # ... and are not on the reference's outline
    differing_off_outline: int  # pixels not bit-identical and not on the reference's outline
    drawn_ref: int              # pixels the reference did not leave as background
    drawn_shown: int

    def __str__(self) -> str:
        return (f"{self.differing} px differ (max {self.max_error}), {self.beyond_lighting} beyond the lighting "
                f"quantisation, {self.beyond_lighting_off_outline} of them off the outline; "
                f"{self.differing_off_outline} px differ off the outline; drawn: reference "
                f"{self.drawn_ref}, firmware {self.drawn_shown}")


def lighting_ok(shown: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """Per pixel: every RGB565 channel of the firmware's is the reference's, one more or one less."""
    delta = rgb565_channels(ref) - rgb565_channels(shown)
    return np.all(np.abs(delta) <= 1, axis=-1)


def compare(shown: np.ndarray, ref: np.ndarray, background=None) -> Comparison:
    shown = np.asarray(shown, dtype=np.int64)
    ref = np.asarray(ref, dtype=np.int64)
    bg = np.asarray(ref[0, 0] if background is None else background)
    error = np.abs(shown - ref).max(axis=-1)
    beyond = ~lighting_ok(shown, ref)
    off = ~outline_mask(ref)
    return Comparison(int((error > 0).sum()), int(error.max()), int(beyond.sum()),
                      int((beyond & off).sum()), int(((error > 0) & off).sum()),
                      int(np.any(ref != bg, axis=-1).sum()), int(np.any(shown != bg, axis=-1).sum()))


@contextlib.contextmanager
def firmware_lighting_in_reference():
    """The reference with the firmware's lighting arithmetic (render.S face_light, shade_rgb565):
    k = round-to-nearest-even(64 I) in single precision (render.S light_level with the default
    light_levels = 65), clamped to 0..64, each RGB565 channel c to floor((c k + 32) / 64)
    (shade_rgb565: rounded to nearest). Everything else stays the reference's float64."""
    original = reference_render.shade

    def shade(colours, intensity):
        k = np.clip(np.rint(np.asarray(intensity, dtype=np.float32) * np.float32(64)), 0, 64).astype(np.int64)
        c = np.asarray(colours, dtype=np.int64)
        r, g, b = (((c >> 11) & 31) * k + 32) >> 6, (((c >> 5) & 63) * k + 32) >> 6, ((c & 31) * k + 32) >> 6
        return ((r << 11) | (g << 5) | b).astype(np.uint16)

    reference_render.shade = shade
    try:
        yield
    finally:
        reference_render.shade = original


def reference_depth(run: Run, frame: int) -> np.ndarray:
    """The reference's float64 depth buffer (z / w, 1.0 = cleared) of a frame."""
    captured = {}
    original = reference_render.Target

    class Capturing(original):
        def __init__(self, background):
            super().__init__(background)
            captured["target"] = self

    reference_render.Target = Capturing
    try:
        scene, mesh, texture = reference.load_card_image(run.card)
        reference.render_frame(scene, mesh, texture, frame)
    finally:
        reference_render.Target = original
    return captured["target"].depth


# --------------------------------------------------------------------------- the heap budget

@dataclass
class HeapLayout:
    """What the firmware's ELF says about its heap: the bounds (k210.ld's __heap_start,
    __heap_end) and the assembler constants the allocations are sized with (each `.equ` is kept
    as an absolute symbol in the ELF's symbol table)."""
    start: int
    end: int
    constants: dict[str, int]

    @property
    def size(self) -> int:
        return self.end - self.start

    def __getattr__(self, name: str) -> int:
        try:
            return self.__dict__["constants"][name]
        except KeyError:
            raise AttributeError(name) from None


NEEDED = ("HEAP_ALIGN", "FAT_SECTOR_BYTES", "MESH_V_BYTES", "MESH_T_BYTES", "MESH_N_BYTES", "MESH_F_BYTES",
          "VTX_BYTES", "WORLD_POS_BYTES", "EDGE_BYTES", "EDGES_PER_TRIANGLE", "DEPTH_BUFFER_BYTES", "DEPTH16_BUFFER_BYTES",
          "NORMAL_LIGHT_SHIFT", "NORMAL_PHONG_SHIFT", "TEX_PIXEL_BYTES", "OBJ_WINDOW_BYTES", "MIP_TABLE_BYTES", "ADJ_BYTES",
          "ADJ_FACE_BYTES", "ADJ_KEY_BYTES", "SUM_BUFFER_BYTES", "WIRE_BUFFER_BYTES")


def heap_layout(elf: Path) -> HeapLayout:
    values = elf_symbols(elf)
    symbols = {name: min(found) for name, found in values.items()}
    clashing = [name for name in NEEDED + ("__heap_start", "__heap_end") if len(values.get(name, ())) > 1]
    assert not clashing, f"{clashing} have several values in the firmware's ELF"
    missing = [name for name in NEEDED + ("__heap_start", "__heap_end") if name not in symbols]
    assert not missing, f"the firmware's ELF no longer has {missing}: update extremes_support.heap_layout"
    assert "depth_buffer" not in symbols, "a static depth buffer again: update extremes_support.boot_allocations"
    start = -(-symbols["__heap_start"] // symbols["HEAP_ALIGN"]) * symbols["HEAP_ALIGN"]
    return HeapLayout(start, symbols["__heap_end"], {name: symbols[name] for name in NEEDED})


class Heap:
    """heap.S's bump allocator: a block of n bytes fits when n <= the bytes free; the next block
    then starts at the next HEAP_ALIGN boundary (or the heap is full). heap_release gives back
    the latest blocks, from a block's address on."""

    def __init__(self, layout: HeapLayout):
        self.layout = layout
        self.next = layout.start
        self.failed: str | None = None

    @property
    def free(self) -> int:
        return self.layout.end - self.next

    def alloc(self, size: int) -> int | None:
        """The block's address, or None when it does not fit (the heap is left as it was)."""
        if size > self.free:
            return None
        align = self.layout.HEAP_ALIGN
        address = self.next
        self.next = min(self.layout.end, -(-(self.next + size) // align) * align)
        return address

    def alloc_or_fail(self, name: str, size: int) -> int | None:
        """heap.S heap_alloc_or_fail: on failure remembers its error 12 line."""
        address = self.alloc(size)
        if address is None:
            self.failed = (f"{MODEL_TOO_LARGE.console_starts[0]} ({name}: {size} bytes needed, "
                           f"{self.free} bytes free)")
        return address

    def release(self, address: int) -> None:
        self.next = address


def boot_allocations(layout: HeapLayout, texture: int | None, vertices: int, texcoords: int, normals: int,
                     triangles: int, wireframe: bool = False, depth: str = "int16", gouraud: bool = False,
                     scene_ini: int | None = None, mipmap: tuple[int, int] | None = None,
                     antialias: str = "off", phong: bool = False) -> tuple[str, Heap]:
    """Replays the firmware's heap use at boot, given the sizes of the files (texture: bytes of
    texture.ppm, None for none; scene_ini likewise) and the model's counts. The model's text
    takes no part: obj.S reads it through a window. In order: scene.S scene_load (scene.ini if
    any, loaded and given back once parsed; the texture, which only textured mode reads (give
    None for a flat or wireframe scene): fat32_load takes its
    size rounded up to whole sectors, error 7 when that does not fit), obj.S obj_parse_model (the
    first pass's window of OBJ_WINDOW_BYTES, given back; the v, vt, vn and triangle arrays, none
    for a count of 0, all four tried before failing: error 12 "model too large for memory: n
    bytes needed, m bytes free"; normals only with `shading = gouraud` (or `phong`: phong = True)
    in a lit mode; the second
    pass's window after them, given back), render.S render_init: vertex.S vertex_init's vertex
    records and, with flat shading in a lit mode, the world positions; then the wireframe edge
    list (and, with `antialias = supersample`, the union lines' cells and spans,
    WIRE_BUFFER_BYTES), or else the
    depth buffer (DEPTH16_BUFFER_BYTES for `depth = int16`, the default; DEPTH_BUFFER_BYTES for
    float32) and, with `shading = gouraud`, one f32 per normal (MESH_NCOUNT <<
    NORMAL_LIGHT_SHIFT; heap.S's heap_alloc of 0 bytes always succeeds; with `phong`, the normal in
    the light's basis, << NORMAL_PHONG_SHIFT), with `antialias = edge`
    the triangle adjacency (render.S adjacency_build: ADJ_FACE_BYTES a triangle, kept; then, given
    back at the end, the canonical vertex indices (ADJ_BYTES a vertex), the vertices' sort keys
    (ADJ_KEY_BYTES a vertex, given back first) and the edges' (three ADJ_KEY_BYTES a triangle)),
    with `antialias = supersample` the sums of the samples (SUM_BUFFER_BYTES),
    and last, with
    `filter = mipmap` (mipmap = the texture's (width, height)), the mip chain (raster.S
    raster_build_mips: `mip_chain_bytes`); each of these blocks is
    error 12 "model too large for memory (<block>: n bytes needed, m bytes free)".
    Returns ("ok" | FILE_TOO_LARGE_OUTCOME | MODEL_TOO_LARGE_OUTCOME, heap); heap.failed is the console line for the block
    that did not fit (for error 7 its start: the line goes on with the file's name and sizes)."""
    gouraud = gouraud or phong          # (per corner either way)
    heap = Heap(layout)
    sector = layout.FAT_SECTOR_BYTES
    for size, kept in ((scene_ini, False), (None if wireframe else texture, True)):
        if size is None:
            continue
        address = heap.alloc(-(-size // sector) * sector)
        if address is None:
            heap.failed = f"{FILE_TOO_LARGE.console_starts[0]}: "
            return FILE_TOO_LARGE_OUTCOME, heap
        if not kept:
            heap.release(address)
    window = heap.alloc_or_fail("model text window", layout.OBJ_WINDOW_BYTES)
    if window is None:
        return MODEL_TOO_LARGE_OUTCOME, heap
    heap.release(window)
    ok, free, needed, align = True, heap.free, 0, layout.HEAP_ALIGN
    for count, each in ((vertices, layout.MESH_V_BYTES), (texcoords, layout.MESH_T_BYTES),
                        (normals, layout.MESH_N_BYTES if gouraud and not wireframe else 0),
                        (triangles, layout.MESH_F_BYTES)):
        if count and each:
            ok = heap.alloc(count * each) is not None and ok
            needed += -(-count * each // align) * align
    if not ok:
        heap.failed = f"{MODEL_TOO_LARGE.console_starts[0]}: {needed} bytes needed, {free} bytes free"
        return MODEL_TOO_LARGE_OUTCOME, heap
    window = heap.alloc_or_fail("model text window", layout.OBJ_WINDOW_BYTES)
    if window is None:
        return MODEL_TOO_LARGE_OUTCOME, heap
    heap.release(window)
    blocks = [("vertex records", vertices * layout.VTX_BYTES)]
    if not wireframe and not gouraud:
        blocks.append(("world positions", vertices * layout.WORLD_POS_BYTES))
    if wireframe:
        blocks.append(("edge list", triangles * layout.EDGES_PER_TRIANGLE * layout.EDGE_BYTES))
        if antialias == "supersample":
            blocks.append(("line coverage cells", layout.WIRE_BUFFER_BYTES))
    else:
        blocks.append(("depth buffer",
                       layout.DEPTH16_BUFFER_BYTES if depth == "int16" else layout.DEPTH_BUFFER_BYTES))
        if gouraud:
            if phong:
                blocks.append(("normals in the light's basis", normals << layout.NORMAL_PHONG_SHIFT))
            else:
                blocks.append(("normal intensities", normals << layout.NORMAL_LIGHT_SHIFT))
        if antialias == "edge":
            blocks.append(("adjacency", triangles * layout.ADJ_FACE_BYTES))
        if antialias == "supersample":
            blocks.append(("supersample sums", layout.SUM_BUFFER_BYTES))
        if mipmap is not None and texture is not None:
            blocks.append(("mip chain", mip_chain_bytes(layout, *mipmap)))
    for name, size in blocks:
        if heap.alloc_or_fail(name, size) is None:
            return MODEL_TOO_LARGE_OUTCOME, heap
        if name == "adjacency" and not _adjacency_scratch(heap, layout, vertices, triangles):
            return MODEL_TOO_LARGE_OUTCOME, heap
    return "ok", heap


def _adjacency_scratch(heap: Heap, layout: HeapLayout, vertices: int, triangles: int) -> bool:
    """render.S adjacency_build's blocks after the adjacency, all given back before it returns:
    the canonical vertex indices, the vertices' sort keys (given back at once), the edges' sort
    keys. False (with heap.failed set) when one does not fit."""
    canonical = heap.alloc_or_fail("canonical vertices", vertices * layout.ADJ_BYTES)
    if canonical is None:
        return False
    keys = heap.alloc_or_fail("vertex keys", vertices * layout.ADJ_KEY_BYTES)
    if keys is None:
        return False
    heap.release(keys)
    if heap.alloc_or_fail("adjacency keys", triangles * layout.EDGES_PER_TRIANGLE * layout.ADJ_KEY_BYTES) is None:
        return False
    heap.release(canonical)
    return True


def mip_chain_bytes(layout: HeapLayout, width: int, height: int) -> int:
    """The "mip chain" block of a width x height texture: the level table, then levels 1 .. L - 1
    (each side halved, rounded down, at least 1; L = the bit length of the longer side)."""
    size, level = layout.MIP_TABLE_BYTES, 1
    while max(width, height) >> level:
        size += max(1, width >> level) * max(1, height >> level) * layout.TEX_PIXEL_BYTES
        level += 1
    return size


def boot_outcomes(layout: HeapLayout, *args, **kwargs) -> set[str]:
    """boot_allocations' outcome, as a set (the callers' interface from when the depth buffer's
    place in the heap order was not known; it is now, so the set has one element)."""
    return {boot_allocations(layout, *args, **kwargs)[0]}


def limits(outcomes, low: int, high: int) -> tuple[int, int]:
    """(the largest n that fits in every order, the smallest n that fits in none) for outcomes
    (n -> set of outcomes), monotone in n, searched in [low, high)."""
    most = largest(lambda n: outcomes(n) == {"ok"}, low, high)
    beyond = largest(lambda n: "ok" in outcomes(n), low, high) + 1
    return most, beyond


def largest(fits, low: int, high: int) -> int:
    """The largest n in [low, high) with fits(n), fits being monotone (true then false)."""
    assert fits(low) and not fits(high)
    while high - low > 1:
        middle = (low + high) // 2
        if fits(middle):
            low = middle
        else:
            high = middle
    return low


# --------------------------------------------------------------------------- textures

def unique_texture(width: int, height: int) -> tuple[bytes, np.ndarray]:
    """A P6 texture whose texels all have different RGB565 colours (texel i: R = i & 31,
    G = (i >> 5) & 63, B = i >> 11, exact through ppm.S's 8-to-5/6-bit rounding), none of them
    magenta (31, 0, 31), the background these scenes use. Returns (file, RGB565 of each texel)."""
    count = width * height
    assert count < 63519, "a texture this large repeats colours"
    index = np.arange(count, dtype=np.int64)
    r5, g6, b5 = index & 31, (index >> 5) & 63, index >> 11
    pixels = np.stack([(r5 << 3) | (r5 >> 2), (g6 << 2) | (g6 >> 4), (b5 << 3) | (b5 >> 2)], axis=-1)
    data = f"P6\n{width} {height}\n255\n".encode() + pixels.astype(np.uint8).tobytes()
    return data, ((r5 << 11) | (g6 << 5) | b5).reshape(height, width)


def texel_index(image: np.ndarray, texels: np.ndarray) -> np.ndarray:
    """Per pixel the index (row * width + column) of the texel whose colour it shows, -1 for
    a colour that is no texel (the background, or something that should not be there)."""
    c = rgb565_channels(image)
    packed = (c[..., 0] << 11) | (c[..., 1] << 5) | c[..., 2]
    flat = texels.ravel()
    order = np.argsort(flat)
    where = np.clip(np.searchsorted(flat[order], packed), 0, len(flat) - 1)
    found = flat[order][where] == packed
    return np.where(found, order[where], -1)


@dataclass
class TexelComparison:
    drawn: int            # pixels both drew
    neighbour: int        # ... showing a texel next to the reference's (wrapping, +-1 per axis)
    farther: int          # ... showing any other texel
    coverage: int         # pixels one drew and the other did not
    not_a_texel: int      # pixels the firmware drew in a colour that is no texel

    def __str__(self) -> str:
        return (f"{self.drawn} px drawn by both: {self.neighbour} show a neighbouring texel, {self.farther} a "
                f"farther one; {self.coverage} px drawn by only one; {self.not_a_texel} px not a texel")


def compare_texels(shown: np.ndarray, ref: np.ndarray, texels: np.ndarray, background) -> TexelComparison:
    height, width = texels.shape
    fw, rf = texel_index(shown, texels), texel_index(ref, texels)
    fw_drawn = np.any(np.asarray(shown) != background, axis=-1)
    rf_drawn = np.any(np.asarray(ref) != background, axis=-1)
    both = (fw >= 0) & (rf >= 0)
    drow = np.abs(fw // width - rf // width)
    dcol = np.abs(fw % width - rf % width)
    drow, dcol = np.minimum(drow, height - drow), np.minimum(dcol, width - dcol)
    same = both & (fw == rf)
    near = both & ~same & (drow <= 1) & (dcol <= 1)
    return TexelComparison(int(both.sum()), int(near.sum()), int((both & ~same & ~near).sum()),
                           int((fw_drawn != rf_drawn).sum()), int((fw_drawn & (fw < 0)).sum()))
