"""The structural similarity index (SSIM) of two images (Wang, Bovik, Sheikh & Simoncelli 2004,
"Image quality assessment: from error visibility to structural similarity", IEEE Trans. Image
Process. 13(4), 600-612).

At every pixel, with the local means, variances and covariance weighted by a Gaussian window
(sigma 1.5 px, 11 x 11, the paper's choice),

    SSIM = (2 mu_x mu_y + C1) (2 sigma_xy + C2)
           / ((mu_x^2 + mu_y^2 + C1) (sigma_x^2 + sigma_y^2 + C2))

with ``C1 = (K1 L)^2``, ``C2 = (K2 L)^2``, ``K1 = 0.01``, ``K2 = 0.03`` and ``L`` the dynamic
range; the index of two images is the mean of the map (here over a mask if given). Colour
images are compared on their luma (ITU-R BT.601 weights), as the paper does on grey levels.
"""

from __future__ import annotations

import numpy as np

K1, K2 = 0.01, 0.03
SIGMA = 1.5  #: px, the Gaussian window's standard deviation
TRUNCATE = 3.5  #: the window reaches 3.5 sigma (11 x 11 pixels at sigma 1.5)
LUMA = np.array([0.299, 0.587, 0.114])


def ssim_map(a: np.ndarray, b: np.ndarray, *, data_range: float = 255.0) -> np.ndarray:
    """The SSIM map (h, w) of two grey (h, w) or RGB (h, w, 3) images of the same shape."""
    from scipy.ndimage import gaussian_filter

    x, y = _grey(a), _grey(b)
    if x.shape != y.shape:
        raise ValueError(f"images of different shapes: {x.shape} and {y.shape}")
    c1, c2 = (K1 * data_range) ** 2, (K2 * data_range) ** 2

    def blur(z):
        return gaussian_filter(z, SIGMA, truncate=TRUNCATE, mode="reflect")

    mx, my = blur(x), blur(y)
    sxx = blur(x * x) - mx * mx
    syy = blur(y * y) - my * my
    sxy = blur(x * y) - mx * my
    return ((2 * mx * my + c1) * (2 * sxy + c2)) / ((mx * mx + my * my + c1) * (sxx + syy + c2))


def ssim(a: np.ndarray, b: np.ndarray, *, mask: np.ndarray | None = None,
         data_range: float = 255.0) -> float:
    """Mean SSIM of two images, over ``mask`` (h, w) bool where given."""
    m = ssim_map(a, b, data_range=data_range)
    if mask is None:
        return float(m.mean())
    mask = np.asarray(mask, bool)
    if not mask.any():
        raise ValueError("the mask selects no pixel")
    return float(m[mask].mean())


def _grey(a: np.ndarray) -> np.ndarray:
    a = np.asarray(a, float)
    if a.ndim == 3:
        return a[..., :3] @ LUMA
    return a
