# suspension_reference.awk - camber and toe of examples/suspension.mech computed independently, against mechc run's CSV.
#
#   awk -F, -v tol=1e-9 -f tests/suspension_reference.awk RUN.csv
#
# Not mechc's method (Newton on 21 Euler-parameter coordinates) but the
# geometry step by step, in the plane and with spheres: for a lower-arm
# angle th, the lower ball L turns about the chassis axis x; the upper ball
# U closes the planar four-bar I_L L U I_U in the plane x = 0 (two circles,
# the closure nearer the design); the steering ball T is where three
# spheres meet (about L, U and the rack end R, radii from the design; the
# point nearer the design); the upright's rotation maps the design triad
# (U - L, T - L) onto the moved one. Bisection on th meets the wheel
# centre's height W_z = 0.28 + s, s = 0.16 (t - 0.5). Then with the spin
# axis a = A (0, 1, 0): camber = asin(-a_z), toe = atan2(a_x, a_y), degrees.
# Prints the worst differences; exits 1 unless every row's camber_deg and
# toe_deg are within tol and there are at least 3 rows.

function sq(x) { return x * x }
function dist2(a, b) { return sq(a[1] - b[1]) + sq(a[2] - b[2]) + sq(a[3] - b[3]) }
function set(v, x, y, z) { v[1] = x; v[2] = y; v[3] = z }
function asin(x) { return atan2(x, sqrt(1 - x * x)) }

# orthonormal triad f1 f2 f3 from the vectors p (first) and r (second)
function triad(p, r, f1, f2, f3,   n, d, k) {
    n = sqrt(p[1] * p[1] + p[2] * p[2] + p[3] * p[3])
    for (k = 1; k <= 3; k++) f1[k] = p[k] / n
    d = r[1] * f1[1] + r[2] * f1[2] + r[3] * f1[3]
    for (k = 1; k <= 3; k++) f2[k] = r[k] - d * f1[k]
    n = sqrt(f2[1] * f2[1] + f2[2] * f2[2] + f2[3] * f2[3])
    for (k = 1; k <= 3; k++) f2[k] /= n
    set(f3, f1[2] * f2[3] - f1[3] * f2[2], f1[3] * f2[1] - f1[1] * f2[3], f1[1] * f2[2] - f1[2] * f2[1])
}

# the upright for lower-arm angle th: sets L U T, the spin axis AX and the
# wheel centre WC
function place(th,   y, z, dy, dz, d, a, h, ey, ez, s1, s2, k, ex, e1, e2, e3, g1, g2, g3, p, r, c1, c2, c3, c4, c5, c6, tx, ty, tz) {
    y = L0[2] - IL[2]; z = L0[3] - IL[3]
    set(L, 0, IL[2] + y * cos(th) - z * sin(th), IL[3] + y * sin(th) + z * cos(th))
    # U: circle about I_U (radius rU) and about L (radius dLU), in x = 0
    dy = L[2] - IU[2]; dz = L[3] - IU[3]; d = sqrt(dy * dy + dz * dz)
    a = (rU2 - dLU2 + d * d) / (2 * d); h = sqrt(rU2 - a * a)
    ey = dy / d; ez = dz / d
    s1 = IU[2] + a * ey - h * ez; s2 = IU[3] + a * ez + h * ey
    c1 = IU[2] + a * ey + h * ez; c2 = IU[3] + a * ez - h * ey
    if (sq(s1 - U0[2]) + sq(s2 - U0[3]) <= sq(c1 - U0[2]) + sq(c2 - U0[3])) set(U, 0, s1, s2)
    else set(U, 0, c1, c2)
    # T: spheres about L, U, R (trilateration in the frame ex, ey, ez)
    for (k = 1; k <= 3; k++) ex[k] = U[k] - L[k]
    d = sqrt(dist2(U, L))
    for (k = 1; k <= 3; k++) { ex[k] /= d; r[k] = R[k] - L[k] }
    p = ex[1] * r[1] + ex[2] * r[2] + ex[3] * r[3]
    for (k = 1; k <= 3; k++) e1[k] = r[k] - p * ex[k]
    h = sqrt(e1[1] * e1[1] + e1[2] * e1[2] + e1[3] * e1[3])
    for (k = 1; k <= 3; k++) e1[k] /= h
    set(e2, ex[2] * e1[3] - ex[3] * e1[2], ex[3] * e1[1] - ex[1] * e1[3], ex[1] * e1[2] - ex[2] * e1[1])
    # T - L = tx ex + ty e1 + tz e2; R - L = p ex + h e1
    tx = (dLT2 - dUT2 + d * d) / (2 * d)
    ty = (dLT2 - dRT2 + p * p + h * h - 2 * p * tx) / (2 * h)
    tz = sqrt(dLT2 - tx * tx - ty * ty)
    for (k = 1; k <= 3; k++) { c3[k] = L[k] + tx * ex[k] + ty * e1[k] + tz * e2[k]; c4[k] = c3[k] - 2 * tz * e2[k] }
    if (dist2(c3, T0) <= dist2(c4, T0)) { for (k = 1; k <= 3; k++) T[k] = c3[k] }
    else { for (k = 1; k <= 3; k++) T[k] = c4[k] }
    # the rotation: design triad (e1 e2 e3) onto the moved one (g1 g2 g3)
    for (k = 1; k <= 3; k++) { c5[k] = U0[k] - L0[k]; c6[k] = T0[k] - L0[k] }
    triad(c5, c6, e1, e2, e3)
    for (k = 1; k <= 3; k++) { c5[k] = U[k] - L[k]; c6[k] = T[k] - L[k] }
    triad(c5, c6, g1, g2, g3)
    for (k = 1; k <= 3; k++) {
        AX[k] = g1[k] * e1[2] + g2[k] * e2[2] + g3[k] * e3[2]
        WC[k] = L[k] + g1[k] * (e1[1] * wl[1] + e1[2] * wl[2] + e1[3] * wl[3]) \
                     + g2[k] * (e2[1] * wl[1] + e2[2] * wl[2] + e2[3] * wl[3]) \
                     + g3[k] * (e3[1] * wl[1] + e3[2] * wl[2] + e3[3] * wl[3])
    }
}

BEGIN {
    pi = atan2(0, -1); deg = pi / 180
    set(IL, 0, 0.20, 0.15); set(L0, 0, 0.62, 0.13)
    set(IU, 0, 0.32, 0.40); set(U0, 0, 0.58, 0.42)
    set(W0, 0, 0.72, 0.28); set(T0, -0.13, 0.64, 0.18); set(R, -0.13, 0.27, 0.19)
    rU2 = dist2(U0, IU); dLU2 = dist2(U0, L0)
    dLT2 = dist2(T0, L0); dUT2 = dist2(T0, U0); dRT2 = dist2(T0, R)
    for (k = 1; k <= 3; k++) wl[k] = W0[k] - L0[k]
    worst_c = worst_t = 0; n = 0
}
NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
{
    s = 0.16 * ($1 - 0.5)
    lo = -0.5; hi = 0.5
    for (it = 0; it < 200; it++) {
        mid = (lo + hi) / 2
        place(mid)
        if (WC[3] < 0.28 + s) lo = mid; else hi = mid
    }
    place((lo + hi) / 2)
    camber = asin(-AX[3]) / deg; toe = atan2(AX[1], AX[2]) / deg
    dc = $(c["camber_deg"]) - camber; if (dc < 0) dc = -dc
    dt = $(c["toe_deg"]) - toe; if (dt < 0) dt = -dt
    if (dc > worst_c) worst_c = dc
    if (dt > worst_t) worst_t = dt
    n++
    if (verbose) printf "t %s travel %.4f camber %.12f toe %.12f\n", $1, s, camber, toe
}
END {
    printf "suspension: %d travels; worst camber difference %.3g deg, toe %.3g deg\n", n, worst_c, worst_t > "/dev/stderr"
    exit !(n >= 3 && ("camber_deg" in c) && ("toe_deg" in c) && worst_c <= tol && worst_t <= tol)
}
