"""The paper's equations 1, 2, 3 and 5 transcribed literally, independent of pressfit (test oracle).

Corrections, each documented where it is used: equation 1 lost its inverse functions (restored as
atan: tan(alpha_1) = y_h / (z_h + p - r), tan(beta_1) = (x_h / y_h) sin(alpha_1)); in equation 2 "y_i"
means y_h; in equation 3 the beta-dot lines divide (x_dot y_h - x_h y_dot) by y_h^2, not y_h;
equation 5 lacks A_14 = cos(beta_4) cos(alpha_4).
atan of the printed quotients is right while every alpha_i < pi/2, i.e. |x_h|, |z_h| < p - r.
Poses x, y, z (m) are arrays of equal shape; results stack the legs on the first axis.
"""

import numpy as np


def equation_1(x, y, z, p, r):
    """(alpha, beta, l), each (4, ...): rad, rad, m."""
    a = np.array([np.arctan(y / (z + p - r)), np.arctan(-y / (x - p + r)),
                  np.arctan(-y / (z - p + r)), np.arctan(y / (x + p - r))])
    b = np.array([np.arctan(x / y * np.sin(a[0])), np.arctan(z / y * np.sin(a[1])),
                  np.arctan(-x / y * np.sin(a[2])), np.arctan(z / y * np.sin(a[3]))])
    return a, b, y / (np.cos(b) * np.sin(a))


def equation_3(x, y, z, p, r, xd, yd, zd, beta_denominator_power=2):
    """(alpha_dot, beta_dot), each (4, ...), rad/s for a plate velocity (xd, yd, zd) in m/s.

    ``beta_denominator_power=1`` is the printed (wrong) y_h in the beta-dot lines.
    """
    a, b, _ = equation_1(x, y, z, p, r)
    ad = np.array([np.cos(a[0]) ** 2 * (yd * (z + p - r) - zd * y) / (z + p - r) ** 2,
                   np.cos(a[1]) ** 2 * (-yd * (x - p + r) + xd * y) / (x - p + r) ** 2,
                   np.cos(a[2]) ** 2 * (-yd * (z - p + r) + zd * y) / (z - p + r) ** 2,
                   np.cos(a[3]) ** 2 * (yd * (x + p - r) - xd * y) / (x + p - r) ** 2])
    q = y**beta_denominator_power
    bd = np.array([np.cos(b[0]) ** 2 * (ad[0] * np.cos(a[0]) * x / y + (xd * y - x * yd) / q * np.sin(a[0])),
                   np.cos(b[1]) ** 2 * (ad[1] * np.cos(a[1]) * z / y + (zd * y - z * yd) / q * np.sin(a[1])),
                   -np.cos(b[2]) ** 2 * (ad[2] * np.cos(a[2]) * x / y + (xd * y - x * yd) / q * np.sin(a[2])),
                   np.cos(b[3]) ** 2 * (ad[3] * np.cos(a[3]) * z / y + (zd * y - z * yd) / q * np.sin(a[3]))])
    return ad, bd


def equation_2(x, y, z, p, r, xd, yd, zd, beta_denominator_power=2):
    """Leg-length rates l_dot (4, ...), m/s, with y_i read as y_h."""
    a, b, _ = equation_1(x, y, z, p, r)
    ad, bd = equation_3(x, y, z, p, r, xd, yd, zd, beta_denominator_power)
    return (yd * np.cos(b) * np.sin(a) - y * (-bd * np.sin(b) * np.sin(a) + ad * np.cos(b) * np.cos(a))) / (
        np.cos(b) * np.sin(a)) ** 2


def equation_5(x, y, z, p, r, a14=True):
    """A (3, 4, ...) as printed; ``a14=False`` keeps the printed omission (A_14 = 0)."""
    a, b, _ = equation_1(x, y, z, p, r)
    ca, sa, cb, sb = np.cos(a), np.sin(a), np.cos(b), np.sin(b)
    return np.array([
        [sb[0], -cb[1] * ca[1], -sb[2], cb[3] * ca[3] if a14 else 0 * x],
        [cb[0] * sa[0], cb[1] * sa[1], cb[2] * sa[2], cb[3] * sa[3]],
        [cb[0] * ca[0], sb[1], -cb[2] * ca[2], sb[3]],
    ])
