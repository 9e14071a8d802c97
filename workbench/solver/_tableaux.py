"""Butcher tableaux of the embedded Runge–Kutta pairs.

The coefficients are the published ones of Dormand & Prince (1980, J. Comput. Appl. Math. 6:19)
for DOPRI5 with Shampine's (1986) continuous extension, and of Hairer's DOP853 (Hairer, Nørsett &
Wanner 1993, *Solving ODEs I*, Sec. II.10) with its 7th-order dense output. They are taken from
the class attributes of :class:`scipy.integrate.RK45` and :class:`scipy.integrate.DOP853` so that
the compiled integrators and the scipy reference backend use bit-identical numbers.

ARK5(4)8L[2]SA is the additive (implicit–explicit) pair of Kennedy & Carpenter (2003, Appl.
Numer. Math. 44:139, Sec. 5 and Appendix C): an explicit and an L-stable, stiffly accurate
ESDIRK table (diagonal gamma = 41/200) with shared nodes and weights, 5th-order solution and
4th-order embedded solution for the additive system; the rationals are the published ones.
"""

from __future__ import annotations

from fractions import Fraction as F

import numpy as np
from scipy.integrate import DOP853, RK45


def _c(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float64)


# DOPRI5: 6 stages + FSAL, 5th-order solution, 4th-order error estimator, 4th-order dense output.
RK45_A = _c(RK45.A)
RK45_B = _c(RK45.B)
RK45_C = _c(RK45.C)
RK45_E = _c(RK45.E)
RK45_P = _c(RK45.P)

# DOP853: 12 stages + FSAL, 8th-order solution, 5th- and 3rd-order error estimators,
# 3 extra stages for the 7th-order dense output.
DOP853_A = _c(DOP853.A)
DOP853_B = _c(DOP853.B)
DOP853_C = _c(DOP853.C)
DOP853_E3 = _c(DOP853.E3)
DOP853_E5 = _c(DOP853.E5)
DOP853_D = _c(DOP853.D)
DOP853_A_EXTRA = _c(DOP853.A_EXTRA)
DOP853_C_EXTRA = _c(DOP853.C_EXTRA)

# ARK5(4)8L[2]SA: 8 stages (the first explicit in both tables), the implicit diagonal constant.
_ARK_AE = [
    [0, 0, 0, 0, 0, 0, 0, 0],
    [F(41, 100), 0, 0, 0, 0, 0, 0, 0],
    [F(367902744464, 2072280473677), F(677623207551, 8224143866563), 0, 0, 0, 0, 0, 0],
    [F(1268023523408, 10340822734521), 0, F(1029933939417, 13636558850479), 0, 0, 0, 0, 0],
    [
        F(14463281900351, 6315353703477),
        0,
        F(66114435211212, 5879490589093),
        F(-54053170152839, 4284798021562),
        0,
        0,
        0,
        0,
    ],
    [
        F(14090043504691, 34967701212078),
        0,
        F(15191511035443, 11219624916014),
        F(-18461159152457, 12425892160975),
        F(-281667163811, 9011619295870),
        0,
        0,
        0,
    ],
    [
        F(19230459214898, 13134317526959),
        0,
        F(21275331358303, 2942455364971),
        F(-38145345988419, 4862620318723),
        F(-1, 8),
        F(-1, 8),
        0,
        0,
    ],
    [
        F(-19977161125411, 11928030595625),
        0,
        F(-40795976796054, 6384907823539),
        F(177454434618887, 12078138498510),
        F(782672205425, 8267701900261),
        F(-69563011059811, 9646580694205),
        F(7356628210526, 4942186776405),
        0,
    ],
]
_ARK_AI = [
    [0, 0, 0, 0, 0, 0, 0, 0],
    [F(41, 200), F(41, 200), 0, 0, 0, 0, 0, 0],
    [F(41, 400), F(-567603406766, 11931857230679), F(41, 200), 0, 0, 0, 0, 0],
    [F(683785636431, 9252920307686), 0, F(-110385047103, 1367015193373), F(41, 200), 0, 0, 0, 0],
    [
        F(3016520224154, 10081342136671),
        0,
        F(30586259806659, 12414158314087),
        F(-22760509404356, 11113319521817),
        F(41, 200),
        0,
        0,
        0,
    ],
    [
        F(218866479029, 1489978393911),
        0,
        F(638256894668, 5436446318841),
        F(-1179710474555, 5321154724896),
        F(-60928119172, 8023461067671),
        F(41, 200),
        0,
        0,
    ],
    [
        F(1020004230633, 5715676835656),
        0,
        F(25762820946817, 25263940353407),
        F(-2161375909145, 9755907335909),
        F(-211217309593, 5846859502534),
        F(-4269925059573, 7827059040749),
        F(41, 200),
        0,
    ],
    [
        F(-872700587467, 9133579230613),
        0,
        0,
        F(22348218063261, 9555858737531),
        F(-1143369518992, 8141816002931),
        F(-39379526789629, 19018526304540),
        F(32727382324388, 42900044865799),
        F(41, 200),
    ],
]
_ARK_B = _ARK_AI[7]  # stiffly accurate: the weights are the implicit table's last row
_ARK_BHAT = [
    F(-975461918565, 9796059967033),
    0,
    0,
    F(78070527104295, 32432590147079),
    F(-548382580838, 3424219808633),
    F(-33438840321285, 15594753105479),
    F(3629800801594, 4656183773603),
    F(4035322873751, 18575991585200),
]
_ARK_C = [
    0,
    F(41, 100),
    F(2935347310677, 11292855782101),
    F(1426016391358, 7196633302097),
    F(92, 100),
    F(24, 100),
    F(3, 5),
    1,
]

ARK_AE = _c([[float(v) for v in row] for row in _ARK_AE])
ARK_AI = _c([[float(v) for v in row] for row in _ARK_AI])
ARK_B = _c([float(v) for v in _ARK_B])
ARK_E = _c([float(b - bh) for b, bh in zip(_ARK_B, _ARK_BHAT, strict=True)])
ARK_C = _c([float(v) for v in _ARK_C])
ARK_GAMMA = float(_ARK_AI[1][1])

# Step-size controller constants (as scipy and Hairer's codes): safety factor and bounds of the
# step-size ratio.
SAFETY = 0.9
MIN_FACTOR = 0.2
MAX_FACTOR = 10.0


def _radau_iia() -> dict[str, np.ndarray | float]:
    """Radau IIA of order 5 (s = 3; Hairer & Wanner 1996, Sec. IV.5, Table 5.6) in the form of
    their code RADAU5 (Sec. IV.8): the transformation T that block-diagonalises A^-1 into the
    real eigenvalue gamma and the complex pair alpha +- i beta, so that the Newton system of the
    3n stage increments splits into one real and one complex n x n system; the error estimate's
    weights (Eq. 8.20, divided by gamma0 = 1 / gamma); and the collocation polynomial's
    coefficients for dense output.

    T is normalised as in ``scipy.integrate.Radau``: its last row is (1, 1, 0), i.e. the
    eigenvectors' last components are 1.
    """
    s6 = np.sqrt(6.0)
    c = np.array([(4.0 - s6) / 10.0, (4.0 + s6) / 10.0, 1.0])
    a = np.array(
        [
            [(88.0 - 7.0 * s6) / 360.0, (296.0 - 169.0 * s6) / 1800.0, (-2.0 + 3.0 * s6) / 225.0],
            [(296.0 + 169.0 * s6) / 1800.0, (88.0 + 7.0 * s6) / 360.0, (-2.0 - 3.0 * s6) / 225.0],
            [(16.0 - s6) / 36.0, (16.0 + s6) / 36.0, 1.0 / 9.0],
        ]
    )
    lam, vec = np.linalg.eig(np.linalg.inv(a))
    real = int(np.argmin(np.abs(lam.imag)))
    pair = int(np.argmax(lam.imag))  # alpha + i beta, beta > 0
    v_real = vec[:, real].real / vec[2, real].real
    v_pair = vec[:, pair] / vec[2, pair]
    t = np.column_stack([v_real, v_pair.real, v_pair.imag])
    # the collocation polynomial u(t0 + x h) = y0 + sum_k q_k x^(k+1) through u(c_i) = y0 + Z_i:
    # q_k = sum_i P[i, k] Z_i with P = V^-T, V[i, k] = c_i^(k+1)
    vander = np.column_stack([c, c**2, c**3])
    return {
        "A": a,
        "C": c,
        "T": t,
        "TI": np.linalg.inv(t),
        "GAMMA": float(lam[real].real),
        "ALPHA": float(lam[pair].real),
        "BETA": float(lam[pair].imag),
        "E": np.array([-13.0 - 7.0 * s6, -13.0 + 7.0 * s6, -1.0]) / 3.0,
        "P": np.linalg.inv(vander).T.copy(),
    }


_RADAU = _radau_iia()
RADAU_A = _c(_RADAU["A"])
RADAU_C = _c(_RADAU["C"])
RADAU_T = _c(_RADAU["T"])
RADAU_TI = _c(_RADAU["TI"])
RADAU_E = _c(_RADAU["E"])
RADAU_P = _c(_RADAU["P"])
RADAU_GAMMA = _RADAU["GAMMA"]  # real eigenvalue of A^-1 (3.6378...)
RADAU_ALPHA = _RADAU["ALPHA"]  # complex pair alpha +- i beta of A^-1
RADAU_BETA = _RADAU["BETA"]
