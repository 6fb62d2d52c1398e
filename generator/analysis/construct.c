/* construct.c - assembly by construction: what ground, drivers and dyads of revolute joints fix, placed in closed form before Newton.
 *
 * Newton from guesses far from the solution (every angle 0: links lying on
 * top of each other) spends most of its iterations finding the solution's
 * neighbourhood, and from a symmetric guess it may stall. A textbook
 * places a linkage link by link instead: the crank from its driver, then
 * each dyad from the two points it hangs on (Assur groups). That is done
 * here for the planar joints that make most linkages; anything else is left
 * to Newton, which starts from what was placed.
 */
#include "construct.h"

#include "../base/arena.h"
#include "../dag/support.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Rows are solved to this relative accuracy; Newton polishes afterwards. */
#define CONSTRUCT_TOL 1e-13
#define CONSTRUCT_SCALAR_ITER 30

typedef struct Place {
    const Model *m;
    const MechrtKernels *k;     /* Phi: its holonomic rows at t */
    double t;
    double *q;
    bool *known;            /* per coordinate: placed */
    double *phi;            /* nh */
    const Body **owner;     /* per coordinate: the body or point owning it */
    int *at_start, *at;     /* per body (by its first coordinate): the joints
                               attached to it (CSR over coordinates) */
    int placed;
} Place;

typedef struct P2 {
    double x, y;
} P2;

static P2 rotate(double phi, double x, double y)
{
    double c = cos(phi), s = sin(phi);
    return (P2){c * x - s * y, s * x + c * y};
}

static const Body *owner(const Place *p, int q)
{
    return q >= 0 ? p->owner[q] : NULL;
}

/* A body (with an angle) none of whose coordinates is placed yet. */
static bool unplaced_link(const Place *p, const Attach *at)
{
    const Body *b = at->q >= 0 ? owner(p, at->q) : NULL;
    if (!b || !b->has_phi || b->nq != 3)
        return false;
    for (int j = 0; j < b->nq; j++)
        if (p->known[b->q + j])
            return false;
    return true;
}

static bool placed(const Place *p, const Attach *at)
{
    if (at->q < 0)
        return true;
    const Body *b = owner(p, at->q);
    if (!b)
        return false;
    for (int j = 0; j < b->nq; j++)
        if (!p->known[b->q + j])
            return false;
    return true;
}

/* The global position of a placed attachment. */
static P2 point_of(const Place *p, const Attach *at)
{
    if (at->q < 0)
        return (P2){at->sx, at->sy};
    P2 s = at->has_phi ? rotate(p->q[at->q + 2], at->sx, at->sy) : (P2){at->sx, at->sy};
    return (P2){p->q[at->q] + s.x, p->q[at->q + 1] + s.y};
}

static void mark(Place *p, int q)
{
    if (!p->known[q]) {
        p->known[q] = true;
        p->placed++;
    }
}

/* ---- rows with a single unknown ---- */

static double row_at(Place *p, int row)
{
    p->k->phi(p->k->ctx, p->q, p->t, p->phi);
    return p->phi[row];
}

/* Newton on one row for one coordinate; the derivative by central
   differences keeps the cost at a few evaluations of Phi, without the
   dense Jacobian (large mechanisms), and its error only slows the last
   digits, which Newton on every row polishes afterwards. */
static bool solve_scalar(Place *p, int row, int u)
{
    double keep = p->q[u];
    for (int it = 0; it < CONSTRUCT_SCALAR_ITER; it++) {
        double x = p->q[u], h = 1e-6 * (1.0 + fabs(x));
        double f = row_at(p, row);
        if (!isfinite(f))
            break;
        if (fabs(f) <= CONSTRUCT_TOL * (1.0 + fabs(x)))
            return true;
        p->q[u] = x + h;
        double fp = row_at(p, row);
        p->q[u] = x - h;
        double fm = row_at(p, row);
        double d = (fp - fm) / (2.0 * h);
        if (!isfinite(d) || d == 0.0)
            break;
        p->q[u] = x - f / d;
    }
    p->q[u] = keep;
    return false;
}

/* Each holonomic row whose support has one unplaced coordinate fixes it. */
static bool place_single_rows(Place *p, const int *sup_start, const int *sup)
{
    bool progress = false;
    for (int i = 0; i < p->m->nh; i++) {
        int u = -1, unknown = 0;
        for (int k = sup_start[i]; k < sup_start[i + 1]; k++)
            if (!p->known[sup[k]]) {
                u = sup[k];
                unknown++;
            }
        if (unknown == 1 && solve_scalar(p, i, u)) {
            mark(p, u);
            progress = true;
        }
    }
    return progress;
}

/* ---- links and dyads ---- */

/* The link with local points s (at global K) and s2 (at global P):
   its angle (the one nearest the current guess) and position. */
static void set_link(Place *p, int q, P2 K, double sx, double sy, P2 P, double s2x, double s2y)
{
    double phi = atan2(P.y - K.y, P.x - K.x) - atan2(s2y - sy, s2x - sx);
    phi += 2.0 * M_PI * round((p->q[q + 2] - phi) / (2.0 * M_PI));
    P2 s = rotate(phi, sx, sy);
    p->q[q] = K.x - s.x;
    p->q[q + 1] = K.y - s.y;
    p->q[q + 2] = phi;
}

/* How far two placements of a dyad's links (x, y, phi each) are apart:
   angles in radians, positions in units of the dyad's size, so that the
   choice does not depend on the file's length unit. */
static double distance_sq(const double *a, const double *b, double size)
{
    double sum = 0.0;
    for (int i = 0; i < 6; i++) {
        double d = (a[i] - b[i]) / (i % 3 == 2 ? 1.0 : size);
        sum += d * d;
    }
    return sum;
}

/* One side of a dyad: link q pinned at the placed point K (local s) and at
   the middle pin (local s2). */
typedef struct Side {
    int q;
    P2 K;
    double sx, sy, s2x, s2y;
} Side;

static double side_length(const Side *s)
{
    return hypot(s->s2x - s->sx, s->s2y - s->sy);
}

/* The candidate middle pins: both dyad closures, the left one first. Puts
   each link where its candidate says and keeps the one nearer the guess. */
static void close_dyad(Place *p, const Side *a, const Side *b, const P2 cand[2], int ncand,
                       double s2_phi_known)
{
    double guess[6], best[6], trial[6];
    memcpy(guess, p->q + a->q, 3 * sizeof *guess);
    memcpy(guess + 3, p->q + b->q, 3 * sizeof *guess);
    double best_d = INFINITY;
    for (int c = 0; c < ncand; c++) {
        memcpy(p->q + a->q, guess, 3 * sizeof *guess);
        memcpy(p->q + b->q, guess + 3, 3 * sizeof *guess);
        set_link(p, a->q, a->K, a->sx, a->sy, cand[c], a->s2x, a->s2y);
        if (isnan(s2_phi_known)) {
            set_link(p, b->q, b->K, b->sx, b->sy, cand[c], b->s2x, b->s2y);
        } else {        /* the slider keeps its angle: its pin is at cand */
            P2 s = rotate(s2_phi_known, b->s2x, b->s2y);
            p->q[b->q] = cand[c].x - s.x;
            p->q[b->q + 1] = cand[c].y - s.y;
        }
        memcpy(trial, p->q + a->q, 3 * sizeof *trial);
        memcpy(trial + 3, p->q + b->q, 3 * sizeof *trial);
        double d = distance_sq(trial, guess, side_length(a) + side_length(b));
        if (d < best_d * (1.0 - 1e-9)) {
            best_d = d;
            memcpy(best, trial, sizeof best);
        }
    }
    memcpy(p->q + a->q, best, 3 * sizeof *best);
    memcpy(p->q + b->q, best + 3, 3 * sizeof *best);
    for (int j = 0; j < 3; j++) {
        mark(p, a->q + j);
        mark(p, b->q + j);
    }
}

/* Intersections of the circles (K1, l1) and (K2, l2), the left one (seen
   from K1 towards K2) first. */
static int circles(P2 K1, double l1, P2 K2, double l2, P2 out[2])
{
    double dx = K2.x - K1.x, dy = K2.y - K1.y, d = hypot(dx, dy);
    if (!(d > 0.0) || d > l1 + l2 || d < fabs(l1 - l2))
        return 0;
    double a = (l1 * l1 - l2 * l2 + d * d) / (2.0 * d);
    double h = sqrt(fmax(0.0, l1 * l1 - a * a));
    double ex = dx / d, ey = dy / d;
    P2 mid = {K1.x + a * ex, K1.y + a * ey};
    out[0] = (P2){mid.x - h * ey, mid.y + h * ex};
    out[1] = (P2){mid.x + h * ey, mid.y - h * ex};
    return 2;
}

/* Intersections of the circle (K, l) with the line n . P = c (|n| = 1),
   the one ahead along the line's direction (n.y, -n.x) first. */
static int circle_line(P2 K, double l, P2 n, double c, P2 out[2])
{
    double e = c - (n.x * K.x + n.y * K.y);
    if (fabs(e) > l)
        return 0;
    double h = sqrt(fmax(0.0, l * l - e * e));
    P2 foot = {K.x + e * n.x, K.y + e * n.y}, dir = {n.y, -n.x};
    out[0] = (P2){foot.x + h * dir.x, foot.y + h * dir.y};
    out[1] = (P2){foot.x - h * dir.x, foot.y - h * dir.y};
    return 2;
}

/* The revolute joint other than `not1` and `not2` that pins link q (by its
   attachment `self`) to a placed point `other`. */
static const Joint *pin_to_placed(const Place *p, int q, int not1, int not2, const Attach **self,
                                  const Attach **other)
{
    for (int k = p->at_start[q]; k < p->at_start[q + 1]; k++) {
        int j = p->at[k];
        const Joint *J = &p->m->joints[j];
        if (J->kind != JOINT_REVOLUTE || j == not1 || j == not2)
            continue;
        if (J->a.q == q && placed(p, &J->b))
            *self = &J->a, *other = &J->b;
        else if (J->b.q == q && placed(p, &J->a))
            *self = &J->b, *other = &J->a;
        else
            continue;
        return J;
    }
    return NULL;
}

static Side side_of(const Place *p, const Attach *self, const Attach *other, const Attach *mid)
{
    return (Side){self->q, point_of(p, other), self->sx, self->sy, mid->sx, mid->sy};
}

/* A link pinned at two placed points. */
static bool place_two_pins(Place *p, const Joint *J1, const Attach *self, const Attach *other)
{
    int j1 = (int)(J1 - p->m->joints);
    const Attach *self2, *other2;
    if (!pin_to_placed(p, self->q, j1, -1, &self2, &other2))
        return false;
    Side a = side_of(p, self, other, self2);
    if (!(side_length(&a) > 0.0))
        return false;
    set_link(p, a.q, a.K, a.sx, a.sy, point_of(p, other2), a.s2x, a.s2y);
    for (int k = 0; k < 3; k++)
        mark(p, a.q + k);
    return true;
}

/* The RRR dyad whose middle pin is joint j (links on both sides unplaced,
   each pinned to a placed point), or the RRP dyad whose second link keeps
   a placed angle and slides on a placed line (prismatic or pointline). */
static bool place_dyad(Place *p, int j)
{
    const Joint *M = &p->m->joints[j];
    for (int flip = 0; flip < 2; flip++) {
        const Attach *ma = flip ? &M->b : &M->a, *mb = flip ? &M->a : &M->b;
        const Attach *sa, *oa;
        const Joint *J1 = unplaced_link(p, ma) ? pin_to_placed(p, ma->q, j, -1, &sa, &oa) : NULL;
        if (!J1)
            continue;
        Side a = side_of(p, sa, oa, ma);
        P2 cand[2];
        if (unplaced_link(p, mb)) {
            const Attach *sb, *ob;
            if (!pin_to_placed(p, mb->q, j, (int)(J1 - p->m->joints), &sb, &ob))
                continue;
            Side b = side_of(p, sb, ob, mb);
            int n = circles(a.K, side_length(&a), b.K, side_length(&b), cand);
            if (n == 0 || !(side_length(&a) > 0.0) || !(side_length(&b) > 0.0))
                continue;
            close_dyad(p, &a, &b, cand, n, NAN);
            return true;
        }
        /* RRP: mb's body has its angle placed but not all its position
           (the row of the line may have placed one coordinate) */
        const Body *bb = mb->q >= 0 ? owner(p, mb->q) : NULL;
        if (!bb || !bb->has_phi || !p->known[bb->q + 2] || (p->known[bb->q] && p->known[bb->q + 1]))
            continue;
        for (int k = p->at_start[bb->q]; k < p->at_start[bb->q + 1]; k++) {
            const Joint *L = &p->m->joints[p->at[k]];
            if ((L->kind != JOINT_PRISMATIC && L->kind != JOINT_POINTLINE) || L->b.q != bb->q ||
                !placed(p, &L->a))
                continue;
            double phi_a = L->a.q >= 0 && L->a.has_phi ? p->q[L->a.q + 2] : 0.0;
            P2 n = rotate(phi_a, -L->uy, L->ux);
            double len = hypot(n.x, n.y);
            if (!(len > 0.0))
                continue;
            n.x /= len, n.y /= len;
            /* the slid point is the pin plus a placed offset */
            double phi_b = p->q[bb->q + 2];
            P2 off = rotate(phi_b, L->b.sx - mb->sx, L->b.sy - mb->sy);
            P2 pa = point_of(p, &L->a);
            double c = n.x * (pa.x - off.x) + n.y * (pa.y - off.y);
            if (!(side_length(&a) > 0.0) || circle_line(a.K, side_length(&a), n, c, cand) == 0)
                continue;
            Side b = {mb->q, {0, 0}, mb->sx, mb->sy, mb->sx, mb->sy};   /* no length */
            close_dyad(p, &a, &b, cand, 2, phi_b);
            return true;
        }
    }
    return false;
}

/* One pass over the revolute joints (in file order, so a chain written
   from ground outwards is placed in one pass). */
static bool place_links(Place *p)
{
    bool progress = false;
    for (int j = 0; j < p->m->njoints; j++) {
        const Joint *J = &p->m->joints[j];
        if (J->kind != JOINT_REVOLUTE)
            continue;
        if (unplaced_link(p, &J->a) && placed(p, &J->b) && place_two_pins(p, J, &J->a, &J->b))
            progress = true;
        else if (unplaced_link(p, &J->b) && placed(p, &J->a) && place_two_pins(p, J, &J->b, &J->a))
            progress = true;
        else if (place_dyad(p, j))
            progress = true;
    }
    return progress;
}

/* Who owns each coordinate, and the joints at each body (CSR). */
static void index_bodies(Place *p)
{
    const Model *m = p->m;
    size_t nq = (size_t)m->nq;
    p->owner = xcalloc(nq + 1, sizeof *p->owner);
    p->at_start = xcalloc(nq + 2, sizeof *p->at_start);
    p->at = xcalloc(2 * (size_t)m->njoints + 1, sizeof *p->at);
    for (int i = 0; i < m->nbodies; i++)
        for (int j = 0; j < m->bodies[i].nq; j++)
            p->owner[m->bodies[i].q + j] = &m->bodies[i];
    for (int pass = 0; pass < 2; pass++) {
        int *fill = pass ? xcalloc(nq + 1, sizeof *fill) : NULL;
        for (int j = 0; j < m->njoints; j++) {
            const Attach *ends[2] = {&m->joints[j].a, &m->joints[j].b};
            for (int e = 0; e < 2; e++) {
                int q = ends[e]->q;
                if (q < 0 || q >= m->nq || (e == 1 && q == ends[0]->q))
                    continue;
                if (pass == 0)
                    p->at_start[q + 1]++;
                else
                    p->at[p->at_start[q] + fill[q]++] = j;
            }
        }
        if (pass == 0)
            for (size_t q = 0; q < nq; q++)
                p->at_start[q + 1] += p->at_start[q];
        free(fill);
    }
}

/* The coordinates each holonomic row depends on (CSR). */
static int *row_supports(const Model *m, int **start)
{
    SupportScan scan;
    support_init(&scan);
    int *buf = xmalloc((size_t)m->nq * sizeof *buf + 1);
    int *sup = NULL, n = 0, cap = 0;
    *start = xcalloc((size_t)m->nh + 1, sizeof **start);
    for (int i = 0; i < m->nh; i++) {
        int k = support_collect(&scan, &m->dag, m->rows[i].expr, OP_VAR, buf);
        if (n + k > cap) {
            cap = 2 * (n + k) + 16;
            sup = xrealloc(sup, (size_t)cap, sizeof *sup);
        }
        memcpy(sup + n, buf, (size_t)k * sizeof *buf);
        n += k;
        (*start)[i + 1] = n;
    }
    free(buf);
    support_free(&scan);
    return sup;
}

int construct_with_kernels(const Model *m, const MechrtKernels *k, double t, double *q)
{
    if (m->nh == 0)
        return 0;
    size_t nq = (size_t)m->nq, nh = (size_t)m->nh;
    Place p = {
        .m = m, .k = k, .t = t, .q = q,
        .known = xcalloc(nq, sizeof *p.known),
        .phi = xcalloc(nh, sizeof *p.phi),
    };
    index_bodies(&p);
    int *start, *sup = row_supports(m, &start);
    while (place_single_rows(&p, start, sup) || place_links(&p))
        ;
    free(sup), free(start);
    free(p.known), free(p.phi), free(p.owner), free(p.at_start), free(p.at);
    return p.placed;
}
