"""Sensor noise for synthetic contact masks: what a real imaging table adds."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from graspenv.surface import _checks

__all__ = ["TABLE_NOISE", "SensorNoise", "as_mask"]


def as_mask(mask: NDArray[np.generic], name: str = "mask") -> NDArray[np.bool_]:
    """A contact mask (shape (H, W), bool or integer, non-zero = touched) as booleans.

    Raises:
        ValueError: not two-dimensional, or not of a boolean or integer dtype.
    """
    array = np.asarray(mask)
    if array.ndim != 2:
        raise ValueError(f"{name} must have shape (H, W), got shape {array.shape}")
    if not (array.dtype == np.bool_ or np.issubdtype(array.dtype, np.integer)):
        raise ValueError(f"{name} must be bool or an integer dtype, got {array.dtype}")
    return array != 0


@dataclass(frozen=True)
class SensorNoise:
    """Imperfections of a camera-based touch table, all off by default.

    :meth:`apply` adds them in the order a table would: optical blur of the image
    before it is thresholded, edges that wobble where the threshold meets a noisy
    image, holes where a contact reflects too little light, then independent pixel
    errors.

    Attributes:
        blur_sigma: Gaussian blur of the mask before re-thresholding at half, pixels.
            Rounds corners and erases features narrower than about the sigma.
        salt_pepper: probability that each pixel is flipped (touched ↔ untouched).
        holes: number of dropout holes, each centred on a random touched pixel.
        hole_radius: radius of each hole, pixels.
        jitter: largest distance the contact edges move in or out, pixels.
        jitter_scale: distance along an edge over which the jitter varies, pixels.

    Raises:
        ValueError: a value is out of range; the message names the field.
    """

    blur_sigma: float = 0.0
    salt_pepper: float = 0.0
    holes: int = 0
    hole_radius: float = 3.0
    jitter: float = 0.0
    jitter_scale: float = 8.0

    def __post_init__(self) -> None:
        _checks.non_negative(self.blur_sigma, "blur_sigma")
        probability = _checks.finite(self.salt_pepper, "salt_pepper")
        if not 0.0 <= probability <= 1.0:
            raise ValueError(f"salt_pepper must be a probability in [0, 1], got {probability!r}")
        _checks.count(self.holes, "holes")
        _checks.positive(self.hole_radius, "hole_radius")
        _checks.non_negative(self.jitter, "jitter")
        _checks.positive(self.jitter_scale, "jitter_scale")

    def scaled(self, factor: float) -> SensorNoise:
        """This noise ``factor`` times as strong: the blur, the flip probability
        (at most 1), the jitter and the number of holes (rounded) scaled; the holes'
        size and the jitter's length scale kept."""
        _checks.non_negative(factor, "factor")
        return dataclasses.replace(
            self,
            blur_sigma=self.blur_sigma * factor,
            salt_pepper=min(1.0, self.salt_pepper * factor),
            holes=round(self.holes * factor),
            jitter=self.jitter * factor,
        )

    @property
    def enabled(self) -> bool:
        """Whether :meth:`apply` can change a mask at all."""
        return self.blur_sigma > 0 or self.needs_rng

    @property
    def needs_rng(self) -> bool:
        """Whether :meth:`apply` draws random numbers (everything but the blur)."""
        return self.salt_pepper > 0 or self.holes > 0 or self.jitter > 0

    def apply(
        self, mask: NDArray[np.generic], rng: np.random.Generator | None = None
    ) -> NDArray[np.uint8]:
        """The mask as the noisy table would see it.

        Args:
            mask: shape (H, W), bool or integer, non-zero = touched; not modified.
            rng: the only source of randomness, required when :attr:`needs_rng`; the
                same generator state gives the same result. Nothing is drawn for
                kinds that are off.

        Returns:
            shape (H, W), uint8, 255 where touched and 0 elsewhere.

        Raises:
            ValueError: the mask is not (H, W) bool or integer, or ``rng`` is missing
                while a random kind of noise is on.
        """
        touched = as_mask(mask)
        if self.needs_rng and not isinstance(rng, np.random.Generator):
            raise ValueError(
                f"rng must be a numpy.random.Generator when salt_pepper, holes or jitter "
                f"is on (seed one for repeatable noise), got {rng!r}"
            )
        if self.blur_sigma > 0:
            touched = self._blur(touched)
        if rng is not None and self.jitter > 0:
            touched = self._jitter(touched, rng)
        if rng is not None and self.holes > 0:
            touched = self._holes(touched, rng)
        if rng is not None and self.salt_pepper > 0:
            touched = touched ^ (rng.random(touched.shape) < self.salt_pepper)
        return touched.astype(np.uint8) * np.uint8(255)

    def _blur(self, touched: NDArray[np.bool_]) -> NDArray[np.bool_]:
        image = touched.astype(np.float32)
        blurred = cv2.GaussianBlur(image, (0, 0), self.blur_sigma, borderType=cv2.BORDER_REPLICATE)
        result: NDArray[np.bool_] = blurred >= 0.5
        return result

    def _jitter(self, touched: NDArray[np.bool_], rng: np.random.Generator) -> NDArray[np.bool_]:
        height, width = touched.shape
        # A smooth random field in [-1, 1]: random values on a coarse grid, interpolated.
        grid = (
            math.ceil(height / self.jitter_scale) + 1,
            math.ceil(width / self.jitter_scale) + 1,
        )
        coarse = rng.uniform(-1.0, 1.0, size=grid).astype(np.float32)
        field = np.clip(cv2.resize(coarse, (width, height), interpolation=cv2.INTER_CUBIC), -1, 1)
        if not touched.any() or touched.all():
            return touched
        # Signed distance to the edge (positive inside, half a pixel at the border
        # pixels), so adding the field moves the edge along its normal by the field.
        inside = cv2.distanceTransform(touched.astype(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
        outside = cv2.distanceTransform(
            (~touched).astype(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE
        )
        level = np.where(touched, inside - 0.5, 0.5 - outside)
        result: NDArray[np.bool_] = level + self.jitter * field > 0.0
        return result

    def _holes(self, touched: NDArray[np.bool_], rng: np.random.Generator) -> NDArray[np.bool_]:
        flat = np.flatnonzero(touched)
        if flat.size == 0:
            return touched
        centres = flat[rng.integers(0, flat.size, size=self.holes)]
        rows, cols = np.divmod(centres, touched.shape[1])
        image = touched.astype(np.uint8)
        shift = 4
        radius = round(self.hole_radius * (1 << shift))
        for row, col in zip(rows.tolist(), cols.tolist(), strict=True):
            cv2.circle(image, (col << shift, row << shift), radius, 0, -1, cv2.LINE_8, shift)
        result: NDArray[np.bool_] = image != 0
        return result


#: The noise of two kinds of camera-based table on the default 640 × 480 camera over
#: a 61 × 46 cm top (about 1 mm a pixel), after the table's own background
#: subtraction and threshold. What each kind is prone to is from the literature; the
#: pixel figures are this project's stated assumptions, not measurements of a
#: particular table (README, "A real sensor's masks"):
#:
#: - ``ftir``: frustrated total internal reflection (Han, UIST 2005). Touches light
#:   up with strong contrast against a dark field, so edges are sharp (blur 0.5 px,
#:   jitter 0.5 px) and few pixels flip (1e-5, about 3 a frame); a dry fingertip
#:   couples poorly to bare acrylic and leaves unlit patches (2 holes of 2 px).
#: - ``di``: diffuse illumination, the kind of Wilson's tables (rear infrared light
#:   reflected by the hand through a diffuser). Lower contrast and the diffuser's
#:   blur (1 px), edges that wobble where the threshold meets camera and ambient
#:   infrared noise (jitter 1 px) and more flipped pixels (1e-4, about 30 a frame);
#:   dark nails and shadows leave holes (2 of 2.5 px).
#:
#: "Seeing through the Fog" (ACM ITS 2010) compares noise reduction on recordings
#: of FTIR and DI tables. ``graspenv bench --noise`` plays grasps at these levels and
#: at two and four times the DI level.
TABLE_NOISE: dict[str, SensorNoise] = {
    "ftir": SensorNoise(blur_sigma=0.5, salt_pepper=1e-5, holes=2, hole_radius=2.0, jitter=0.5),
    "di": SensorNoise(blur_sigma=1.0, salt_pepper=1e-4, holes=2, hole_radius=2.5, jitter=1.0),
}
