"""The toy-text pictures (FrozenLake, CliffWalking, Taxi, Blackjack), drawn with numpy only.

Our own flat designs at Gymnasium's frame sizes (Gymnasium's sprites are its own art): tiles
with thin grid lines, round tokens for agents and passengers, letters from a 5 x 7 pixel font
scaled up. Static layers (a map's tiles, the taxi grid) are drawn once per map and copied.

>>> render_frozen_lake(np.asarray(["SF", "HG"], dtype="c"), 0, None).shape
(128, 128, 3)
>>> render_taxi(0, 0).shape, render_cliff_walking(36).shape
((456, 536, 3), (256, 768, 3))
>>> render_blackjack(15, 10, True, "KS").shape
(376, 384, 3)
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from palaestra.rendering import raster
from palaestra.rendering.raster import Color

# 5 x 7 glyphs: "#" is ink.
_FONT = {
    "0": (" ### ", "#   #", "#  ##", "# # #", "##  #", "#   #", " ### "),
    "1": ("  #  ", " ##  ", "  #  ", "  #  ", "  #  ", "  #  ", " ### "),
    "2": (" ### ", "#   #", "    #", "   # ", "  #  ", " #   ", "#####"),
    "3": ("#####", "   # ", "  #  ", "   # ", "    #", "#   #", " ### "),
    "4": ("   # ", "  ## ", " # # ", "#  # ", "#####", "   # ", "   # "),
    "5": ("#####", "#    ", "#### ", "    #", "    #", "#   #", " ### "),
    "6": ("  ## ", " #   ", "#    ", "#### ", "#   #", "#   #", " ### "),
    "7": ("#####", "    #", "   # ", "  #  ", " #   ", " #   ", " #   "),
    "8": (" ### ", "#   #", "#   #", " ### ", "#   #", "#   #", " ### "),
    "9": (" ### ", "#   #", "#   #", " ####", "    #", "   # ", " ##  "),
    "A": (" ### ", "#   #", "#   #", "#####", "#   #", "#   #", "#   #"),
    "B": ("#### ", "#   #", "#   #", "#### ", "#   #", "#   #", "#### "),
    "C": (" ### ", "#   #", "#    ", "#    ", "#    ", "#   #", " ### "),
    "D": ("#### ", "#   #", "#   #", "#   #", "#   #", "#   #", "#### "),
    "E": ("#####", "#    ", "#    ", "#### ", "#    ", "#    ", "#####"),
    "G": (" ### ", "#   #", "#    ", "# ###", "#   #", "#   #", " ####"),
    "H": ("#   #", "#   #", "#   #", "#####", "#   #", "#   #", "#   #"),
    "J": ("  ###", "   # ", "   # ", "   # ", "   # ", "#  # ", " ##  "),
    "K": ("#   #", "#  # ", "# #  ", "##   ", "# #  ", "#  # ", "#   #"),
    "L": ("#    ", "#    ", "#    ", "#    ", "#    ", "#    ", "#####"),
    "P": ("#### ", "#   #", "#   #", "#### ", "#    ", "#    ", "#    "),
    "Q": (" ### ", "#   #", "#   #", "#   #", "# # #", "#  # ", " ## #"),
    "R": ("#### ", "#   #", "#   #", "#### ", "# #  ", "#  # ", "#   #"),
    "S": (" ####", "#    ", "#    ", " ### ", "    #", "    #", "#### "),
    "U": ("#   #", "#   #", "#   #", "#   #", "#   #", "#   #", " ### "),
    "Y": ("#   #", "#   #", " # # ", "  #  ", "  #  ", "  #  ", "  #  "),
    " ": ("     ",) * 7,
}
_GLYPHS = {
    c: np.array([[ch == "#" for ch in row] for row in rows], dtype=bool)
    for c, rows in _FONT.items()
}

WHITE: Color = (255, 255, 255)
INK: Color = (34, 38, 46)


def text_width(text: str, scale: int) -> int:
    """Pixel width of ``text`` at ``scale`` (5 columns a glyph, 1 between glyphs)."""
    return max(len(text) * 6 - 1, 0) * scale


def draw_text(img: np.ndarray, text: str, x: int, y: int, scale: int, color: Color) -> None:
    """Write ``text`` (digits and the capitals of the font) with its top-left corner at (x, y)."""
    for i, ch in enumerate(text):
        glyph = np.kron(_GLYPHS[ch], np.ones((scale, scale), dtype=bool))
        gx = x + i * 6 * scale
        h, w = glyph.shape
        view = img[max(y, 0) : y + h, max(gx, 0) : gx + w]
        view[glyph[: view.shape[0], : view.shape[1]]] = color


def _centred_text(img: np.ndarray, text: str, cx: int, cy: int, scale: int, color: Color) -> None:
    draw_text(img, text, cx - text_width(text, scale) // 2, cy - 7 * scale // 2, scale, color)


def _rect(img: np.ndarray, x0: int, y0: int, x1: int, y1: int, color: Color) -> None:
    """Fill the pixels ``[y0, y1) x [x0, x1)``."""
    img[max(y0, 0) : max(y1, 0), max(x0, 0) : max(x1, 0)] = color


def _frame_rect(
    img: np.ndarray, x0: int, y0: int, x1: int, y1: int, width: int, color: Color
) -> None:
    """The outline of ``[y0, y1) x [x0, x1)``, ``width`` pixels thick, inside it."""
    _rect(img, x0, y0, x1, y0 + width, color)
    _rect(img, x0, y1 - width, x1, y1, color)
    _rect(img, x0, y0, x0 + width, y1, color)
    _rect(img, x1 - width, y0, x1, y1, color)


def _frozen(img: np.ndarray) -> np.ndarray:
    img.setflags(write=False)  # cached layers are shared: copy before drawing
    return img


def _flag(img: np.ndarray, x: int, y: int, size: int, color: Color) -> None:
    """A pennant on a pole whose foot is at (x, y), ``size`` tall."""
    pole = max(size // 16, 2)
    _rect(img, x, y - size, x + pole, y, INK)
    raster.fill_polygon(
        img,
        [
            (x + pole, y - size),
            (x + pole + size * 0.55, y - size * 0.8),
            (x + pole, y - size * 0.6),
        ],
        color,
    )


def _token(img: np.ndarray, cx: float, cy: float, radius: float, color: Color) -> None:
    """A round piece with a dark rim: the agents of the grid worlds."""
    raster.fill_circle(img, cx, cy, radius, INK)
    raster.fill_circle(img, cx, cy, radius - max(radius / 7, 1.5), color)
    eye = radius / 5
    for dx in (-radius / 3, radius / 3):
        raster.fill_circle(img, cx + dx, cy - radius / 5, eye, WHITE)
        raster.fill_circle(img, cx + dx, cy - radius / 5, eye / 2, INK)


# -- FrozenLake --------------------------------------------------------------------------
_ICE: Color = (214, 236, 248)
_ICE_LINE: Color = (170, 200, 225)
_HOLE: Color = (28, 58, 104)
_HOLE_RIM: Color = (120, 160, 200)
_AGENT: Color = (232, 76, 61)
_GOLD: Color = (242, 183, 5)


def _lake_size(nrow: int, ncol: int) -> tuple[int, int, int, int]:
    """``(H, W, cell_h, cell_w)``: Gymnasium's window of 64 px cells, at most 512 a side."""
    width, height = min(64 * ncol, 512), min(64 * nrow, 512)
    return height, width, height // nrow, width // ncol


@lru_cache(maxsize=8)
def _lake_background(rows: tuple[bytes, ...]) -> np.ndarray:
    nrow, ncol = len(rows), len(rows[0])
    h, w, ch, cw = _lake_size(nrow, ncol)
    img = np.empty((h, w, 3), dtype=np.uint8)
    img[:] = _ICE
    for r, row in enumerate(rows):
        for c, letter in enumerate(row.decode()):
            x0, y0 = c * cw, r * ch
            if letter == "H":
                raster.fill_circle(img, x0 + cw / 2, y0 + ch / 2, min(cw, ch) * 0.42, _HOLE_RIM)
                raster.fill_circle(img, x0 + cw / 2, y0 + ch / 2, min(cw, ch) * 0.36, _HOLE)
            elif letter in "SG":
                scale = max(min(cw, ch) // 24, 1)
                draw_text(img, letter, x0 + 3 * scale, y0 + 3 * scale, scale, INK)
                if letter == "G":
                    _flag(img, x0 + cw // 2, y0 + ch - ch // 6, int(ch * 0.6), _GOLD)
    for r in range(1, nrow):
        img[r * ch, :] = _ICE_LINE
    for c in range(1, ncol):
        img[:, c * cw] = _ICE_LINE
    return _frozen(img)


def render_frozen_lake(desc: np.ndarray, s: int, lastaction: int | None) -> np.ndarray:
    """FrozenLake frame for map ``desc`` (bytes ``[nrow, ncol]``) with the player on ``s``."""
    nrow, ncol = desc.shape
    rows = tuple(b"".join(row) for row in desc.tolist())
    img = _lake_background(rows).copy()
    _, _, ch, cw = _lake_size(nrow, ncol)
    r, c = divmod(int(s), ncol)
    radius = min(cw, ch) * 0.3
    if desc[r, c] == b"H":  # fallen in: only a small head shows above the water
        radius *= 0.6
    _token(img, c * cw + cw / 2, r * ch + ch / 2, radius, _AGENT)
    return img


# -- CliffWalking ------------------------------------------------------------------------
_GRASS: Color = (150, 200, 110)
_GRASS_LINE: Color = (120, 170, 85)
_CLIFF: Color = (72, 62, 58)
_CLIFF_EDGE: Color = (120, 100, 88)
_CELL = 64


@lru_cache(maxsize=1)
def _cliff_background() -> np.ndarray:
    img = np.empty((4 * _CELL, 12 * _CELL, 3), dtype=np.uint8)
    img[:] = _GRASS
    for c in range(1, 11):  # the cliff: row 3, columns 1-10, a drop with a jagged lip
        x0, y0 = c * _CELL, 3 * _CELL
        _rect(img, x0, y0, x0 + _CELL, y0 + _CELL, _CLIFF)
        for k in range(4):
            tx = x0 + k * 16
            raster.fill_polygon(img, [(tx, y0), (tx + 16, y0), (tx + 8, y0 + 10)], _CLIFF_EDGE)
    for r in range(1, 4):
        img[r * _CELL, :] = _GRASS_LINE
    for c in range(1, 12):
        img[:, c * _CELL] = _GRASS_LINE
    draw_text(img, "S", 6, 3 * _CELL + 6, 3, INK)
    draw_text(img, "G", 11 * _CELL + 6, 3 * _CELL + 6, 3, INK)
    _flag(img, 11 * _CELL + 34, 4 * _CELL - 8, 40, _GOLD)
    return _frozen(img)


def render_cliff_walking(s: int) -> np.ndarray:
    """CliffWalking frame ``[256, 768, 3]`` with the walker on state ``s``."""
    img = _cliff_background().copy()
    r, c = divmod(int(s), 12)
    _token(img, c * _CELL + _CELL / 2, r * _CELL + _CELL / 2, 20, _AGENT)
    return img


# -- Taxi --------------------------------------------------------------------------------
TAXI_SIZE = (456, 536)
_T_X0, _T_Y0, _T_CW, _T_CH = 48, 48, 88, 72  # grid origin and cell size
_ROAD: Color = (226, 226, 220)
_ROAD_LINE: Color = (200, 200, 192)
_WALL: Color = (52, 56, 66)
_STANDS: tuple[tuple[int, int, str, Color], ...] = (
    (0, 0, "R", (220, 60, 50)),
    (0, 4, "G", (60, 170, 80)),
    (4, 0, "Y", (235, 190, 30)),
    (4, 3, "B", (50, 100, 210)),
)
_TAXI: Color = (250, 200, 40)
_DEST: Color = (200, 40, 160)
_PASSENGER: Color = (60, 110, 220)
_WALLS = ((0, 1), (3, 0), (3, 2), (4, 0), (4, 2))  # (row, col): a wall east of that cell


def _cell_box(row: int, col: int) -> tuple[int, int, int, int]:
    x0, y0 = _T_X0 + col * _T_CW, _T_Y0 + row * _T_CH
    return x0, y0, x0 + _T_CW, y0 + _T_CH


@lru_cache(maxsize=1)
def _taxi_background() -> np.ndarray:
    h, w = TAXI_SIZE
    img = np.full((h, w, 3), 246, dtype=np.uint8)
    _rect(img, _T_X0, _T_Y0, _T_X0 + 5 * _T_CW, _T_Y0 + 5 * _T_CH, _ROAD)
    for row, col, letter, color in _STANDS:
        x0, y0, x1, y1 = _cell_box(row, col)
        _rect(img, x0 + 6, y0 + 6, x1 - 6, y1 - 6, color)
        draw_text(img, letter, x0 + 10, y0 + 10, 2, WHITE)
    for k in range(1, 5):
        img[_T_Y0 + k * _T_CH, _T_X0 : _T_X0 + 5 * _T_CW] = _ROAD_LINE
        img[_T_Y0 : _T_Y0 + 5 * _T_CH, _T_X0 + k * _T_CW] = _ROAD_LINE
    for row, col in _WALLS:
        x = _T_X0 + (col + 1) * _T_CW
        _rect(img, x - 4, _T_Y0 + row * _T_CH, x + 4, _T_Y0 + (row + 1) * _T_CH, _WALL)
    _frame_rect(img, _T_X0 - 8, _T_Y0 - 8, _T_X0 + 5 * _T_CW + 8, _T_Y0 + 5 * _T_CH + 8, 8, _WALL)
    return _frozen(img)


def _person(img: np.ndarray, cx: float, cy: float, size: float, color: Color) -> None:
    """A passenger: head and shoulders."""
    raster.fill_circle(img, cx, cy - size * 0.45, size * 0.28, INK)
    raster.fill_circle(img, cx, cy - size * 0.45, size * 0.22, (250, 220, 190))
    raster.fill_polygon(
        img,
        [
            (cx - size * 0.4, cy + size * 0.5),
            (cx - size * 0.25, cy - size * 0.1),
            (cx + size * 0.25, cy - size * 0.1),
            (cx + size * 0.4, cy + size * 0.5),
        ],
        color,
    )


def _taxi_car(img: np.ndarray, cx: float, cy: float, orientation: int, full: bool) -> None:
    """The taxi, long side along its heading (0 south, 1 north, 2 east, 3 west)."""
    vertical = orientation < 2
    half_long, half_short = 30, 18
    hx, hy = (half_short, half_long) if vertical else (half_long, half_short)
    for wx in (-1, 1):  # wheels at the four corners
        for wy in (-1, 1):
            raster.fill_circle(
                img,
                cx + wx * (hx - 2),
                cy + wy * (hy - 6) if vertical else cy + wy * (hy - 2),
                6,
                INK,
            )
    body = [(cx - hx, cy - hy), (cx + hx, cy - hy), (cx + hx, cy + hy), (cx - hx, cy + hy)]
    raster.fill_polygon(img, body, INK)
    inner = [
        (cx - hx + 2, cy - hy + 2),
        (cx + hx - 2, cy - hy + 2),
        (cx + hx - 2, cy + hy - 2),
        (cx - hx + 2, cy + hy - 2),
    ]
    raster.fill_polygon(img, inner, _TAXI)
    # The windscreen shows the heading: a dark band at the front.
    dx, dy = {0: (0, 1), 1: (0, -1), 2: (1, 0), 3: (-1, 0)}[orientation]
    fx, fy = cx + dx * (hx - 10), cy + dy * (hy - 10)
    sx, sy = (hx - 5, 4) if vertical else (4, hy - 5)
    raster.fill_polygon(
        img,
        [(fx - sx, fy - sy), (fx + sx, fy - sy), (fx + sx, fy + sy), (fx - sx, fy + sy)],
        (70, 90, 120),
    )
    if full:  # the passenger rides along
        raster.fill_circle(img, cx - dx * 6, cy - dy * 6, 8, INK)
        raster.fill_circle(img, cx - dx * 6, cy - dy * 6, 6, _PASSENGER)


def render_taxi(s: int, orientation: int) -> np.ndarray:
    """Taxi frame ``[456, 536, 3]`` for state ``s``, the taxi facing its last move."""
    row, col, rest = int(s) // 100, (int(s) // 20) % 5, int(s) % 20
    passenger, dest = divmod(rest, 4)
    img = _taxi_background().copy()
    x0, y0, x1, y1 = _cell_box(*_STANDS[dest][:2])
    _frame_rect(img, x0 + 2, y0 + 2, x1 - 2, y1 - 2, 5, _DEST)  # the destination, outlined
    _flag(img, x1 - 18, y1 - 10, 30, _DEST)
    if passenger < 4:
        px0, py0, px1, py1 = _cell_box(*_STANDS[passenger][:2])
        _person(img, (px0 + px1) / 2 + 14, (py0 + py1) / 2 + 4, 36, _PASSENGER)
    tx0, ty0, tx1, ty1 = _cell_box(row, col)
    _taxi_car(img, (tx0 + tx1) / 2, (ty0 + ty1) / 2, orientation, passenger == 4)
    return img


# -- Blackjack ---------------------------------------------------------------------------
BLACKJACK_SIZE = (376, 384)
_FELT: Color = (32, 112, 64)
_FELT_LINE: Color = (48, 140, 84)
_CARD_BACK: Color = (44, 74, 160)
_RED: Color = (200, 40, 40)
_CARD_W, _CARD_H = 80, 112


def _suit(img: np.ndarray, suit: str, cx: float, cy: float, size: float) -> None:
    """A suit sign (C, D, H or S) of about ``size`` pixels, centred at (cx, cy)."""
    color = _RED if suit in "DH" else INK
    r = size / 4
    if suit == "D":
        raster.fill_polygon(
            img,
            [
                (cx, cy - size / 2),
                (cx + size * 0.38, cy),
                (cx, cy + size / 2),
                (cx - size * 0.38, cy),
            ],
            color,
        )
        return
    if suit == "H":
        raster.fill_circle(img, cx - r, cy - r / 2, r, color)
        raster.fill_circle(img, cx + r, cy - r / 2, r, color)
        raster.fill_polygon(
            img, [(cx - 2 * r, cy - r / 4), (cx + 2 * r, cy - r / 4), (cx, cy + size / 2)], color
        )
        return
    if suit == "S":
        raster.fill_circle(img, cx - r, cy + r / 3, r, color)
        raster.fill_circle(img, cx + r, cy + r / 3, r, color)
        raster.fill_polygon(
            img, [(cx - 2 * r, cy + r / 6), (cx + 2 * r, cy + r / 6), (cx, cy - size / 2)], color
        )
    else:  # clubs: three leaves
        raster.fill_circle(img, cx, cy - r, r, color)
        raster.fill_circle(img, cx - r * 1.1, cy + r * 0.4, r, color)
        raster.fill_circle(img, cx + r * 1.1, cy + r * 0.4, r, color)
    raster.fill_polygon(
        img,
        [
            (cx - r / 3, cy),
            (cx + r / 3, cy),
            (cx + r * 0.8, cy + size / 2),
            (cx - r * 0.8, cy + size / 2),
        ],
        color,
    )


@lru_cache(maxsize=1)
def _table() -> np.ndarray:
    h, w = BLACKJACK_SIZE
    img = np.empty((h, w, 3), dtype=np.uint8)
    img[:] = _FELT
    _frame_rect(img, 12, 12, w - 12, h - 12, 3, _FELT_LINE)
    draw_text(img, "DEALER", 40, 32, 2, WHITE)
    draw_text(img, "PLAYER", 40, 208, 2, WHITE)
    # The hidden card: a patterned back.
    x0, y0 = 208, 72
    _rect(img, x0, y0, x0 + _CARD_W, y0 + _CARD_H, WHITE)
    _rect(img, x0 + 5, y0 + 5, x0 + _CARD_W - 5, y0 + _CARD_H - 5, _CARD_BACK)
    for k in range(0, _CARD_W + _CARD_H, 12):
        for t in range(3):
            ys = np.arange(y0 + 8, y0 + _CARD_H - 8)
            xs = x0 + 8 + k - (ys - y0) + t
            ok = (xs >= x0 + 8) & (xs < x0 + _CARD_W - 8)
            img[ys[ok], xs[ok]] = (90, 120, 200)
    return _frozen(img)


def render_blackjack(player_sum: int, dealer_value: int, usable_ace: bool, card: str) -> np.ndarray:
    """Blackjack frame ``[376, 384, 3]``: the dealer's face-up ``card`` (e.g. "KS", "10H"),
    its value, the player's sum and whether an ace counts 11."""
    img = _table().copy()
    draw_text(img, str(int(dealer_value)), 40 + text_width("DEALER", 2) + 12, 32, 2, WHITE)
    x0, y0 = 96, 72
    _rect(img, x0, y0, x0 + _CARD_W, y0 + _CARD_H, (210, 210, 204))
    _rect(img, x0 + 2, y0 + 2, x0 + _CARD_W - 2, y0 + _CARD_H - 2, WHITE)
    rank, suit = card[:-1], card[-1]
    color = _RED if suit in "DH" else INK
    draw_text(img, rank, x0 + 8, y0 + 8, 2, color)
    _suit(img, suit, x0 + 14 + (text_width(rank, 2) - 10) / 2, y0 + 36, 14)
    _suit(img, suit, x0 + _CARD_W / 2, y0 + _CARD_H / 2 + 10, 34)
    _centred_text(img, str(int(player_sum)), BLACKJACK_SIZE[1] // 2, 280, 8, WHITE)
    if usable_ace:
        _centred_text(img, "USABLE ACE", BLACKJACK_SIZE[1] // 2, 340, 2, _GOLD)
    return img
