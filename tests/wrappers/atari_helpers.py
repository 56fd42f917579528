"""Fakes and independent references for the Atari wrapper tests (no ROMs, no OpenCV).

Frame ``n`` (the ``n``-th emulated frame of an episode, 0 after reset) is known in advance, so
a test can say which frames a wrapper pooled; lives drop and the game ends on given frames.
"""

from __future__ import annotations

import types
from typing import Any

import numpy as np

from palaestra.core import Env
from palaestra.spaces import Box, Discrete

HEIGHT, WIDTH = 21, 16


def frame_at(n: int) -> np.ndarray:
    """``(21, 16, 3)`` uint8: a different half of the columns lights up on odd and even
    frames, so the max of two consecutive frames equals neither of them."""
    frame = np.zeros((HEIGHT, WIDTH, 3), np.uint8)
    frame[:, n % 2 :: 2, 0] = (10 * n) % 250 + 1
    frame[:, :, 1] = np.arange(WIDTH, dtype=np.uint8) * 3 + n % 7
    frame[:, :, 2] = np.arange(HEIGHT, dtype=np.uint8)[:, None] * 2
    return frame


def gray_at(n: int) -> np.ndarray:
    """The fake emulator's grayscale screen: a fixed mix, distinct from any RGB channel."""
    f = frame_at(n).astype(np.uint16)
    return ((f[..., 0] + f[..., 1] + 2 * f[..., 2]) // 4).astype(np.uint8)


class FakeALE:
    """The slice of ``ale_py.ALEInterface`` that the wrappers use."""

    def __init__(self, env: FakeAtari) -> None:
        self.env = env

    def lives(self) -> int:
        return self.env.lives

    def getScreenRGB(self, out: np.ndarray) -> None:
        out[...] = frame_at(self.env.frame)

    def getScreenGrayscale(self, out: np.ndarray) -> None:
        out[...] = gray_at(self.env.frame)


class FakeAtari(Env[np.ndarray, int]):
    """``frameskip=1``; reward ``r`` on frame ``r`` for ``r`` in ``rewards``; a life is lost on
    each frame in ``life_loss``; the game is over at ``game_over``. ``actions`` logs every step's
    action and ``resets`` every reset."""

    def __init__(
        self,
        meanings: tuple[str, ...] = ("NOOP", "FIRE", "RIGHT", "LEFT"),
        life_loss: tuple[int, ...] = (),
        game_over: int = 10_000,
        rewards: dict[int, float] | None = None,
        frameskip: int = 1,
        obs_type: str = "rgb",
    ) -> None:
        self.meanings = list(meanings)
        self.life_loss, self.game_over, self.rewards = life_loss, game_over, rewards or {}
        self._frameskip = frameskip
        self.obs_type = obs_type
        self.action_space = Discrete(len(meanings))
        shape = {"rgb": (HEIGHT, WIDTH, 3), "grayscale": (HEIGHT, WIDTH), "ram": (128,)}
        self.observation_space = Box(0, 255, shape[obs_type], np.uint8)
        self.ale = FakeALE(self)
        self.frame, self.lives = 0, 1 + len(life_loss)
        self.actions: list[int] = []
        self.resets = 0

    def get_action_meanings(self) -> list[str]:
        return list(self.meanings)

    def _obs(self) -> np.ndarray:
        if self.obs_type == "grayscale":
            return gray_at(self.frame)
        return frame_at(self.frame)

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        self.frame, self.lives = 0, 1 + len(self.life_loss)
        self.resets += 1
        return self._obs(), {"lives": self.lives, "frame": 0}

    def step(self, action: int) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        self.actions.append(int(action))
        self.frame += 1
        if self.frame in self.life_loss:
            self.lives -= 1
        terminated = self.frame >= self.game_over
        reward = float(self.rewards.get(self.frame, 0.0))
        return self._obs(), reward, terminated, False, {"lives": self.lives, "frame": self.frame}


# --- independent references -------------------------------------------------------------------


def area_average(image: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Area-weighted downscale in float64 (no rounding): each output pixel is the mean of the
    source rectangle it covers, fractional cells weighted by their overlap. Written from the
    definition, independently of ``resize_area``'s OpenCV-ordered float32 sums."""

    def weights(src: int, dst: int) -> np.ndarray:
        m = np.zeros((dst, src))
        scale = src / dst
        for d in range(dst):
            lo, hi = d * scale, (d + 1) * scale
            for s in range(int(np.floor(lo)), min(int(np.ceil(hi)), src)):
                m[d, s] = max(0.0, min(hi, s + 1) - max(lo, s))
        return m / m.sum(axis=1, keepdims=True)

    wy, wx = weights(image.shape[0], shape[0]), weights(image.shape[1], shape[1])
    rows = np.tensordot(wy, image.astype(np.float64), axes=(1, 0))  # [h, W, ...]
    return np.moveaxis(np.tensordot(rows, wx, axes=(1, 1)), -1, 1)  # [h, w, ...]


def opencv_gray(frame: np.ndarray) -> np.ndarray:
    """``cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY)`` in integer arithmetic: BT.601 weights
    9798, 19235, 3735 over 2**15, rounded half up (what OpenCV 5 computes on every colour;
    test_atari_wrappers checks this against the installed OpenCV)."""
    f = frame.astype(np.int64)
    luma = f[..., 0] * 9798 + f[..., 1] * 19235 + f[..., 2] * 3735
    return ((luma + (1 << 14)) >> 15).astype(np.uint8)


def fake_cv2() -> types.ModuleType:
    """A minimal ``cv2`` for running Gymnasium's and SB3's wrapper logic where OpenCV is not
    installed: ``resize`` is palaestra's ``resize_area`` (pinned to OpenCV's INTER_AREA bytes by
    tests/wrappers/test_resize.py) and ``cvtColor`` is :func:`opencv_gray`."""
    from palaestra.wrappers.resize import resize_area

    cv2 = types.ModuleType("cv2")
    cv2.INTER_AREA = 3  # type: ignore[attr-defined]
    cv2.COLOR_RGB2GRAY = 7  # type: ignore[attr-defined]
    cv2.ocl = types.SimpleNamespace(setUseOpenCL=lambda flag: None)  # type: ignore[attr-defined]

    def resize(src: np.ndarray, dsize: tuple[int, int], interpolation: int) -> np.ndarray:
        assert interpolation == cv2.INTER_AREA  # type: ignore[attr-defined]
        return resize_area(src, (dsize[1], dsize[0]))

    def cvt_color(src: np.ndarray, code: int) -> np.ndarray:
        assert code == cv2.COLOR_RGB2GRAY  # type: ignore[attr-defined]
        return opencv_gray(src)

    cv2.resize = resize  # type: ignore[attr-defined]
    cv2.cvtColor = cvt_color  # type: ignore[attr-defined]
    return cv2
