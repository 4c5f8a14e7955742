/* drape's explicit step, one element or node at a time: the arithmetic the
 * CUDA kernels run (kernels/cuda.cu, compiled at run time by NVRTC) and the
 * CPU build of the same source (kernels/host.c, compiled by build.rs), so
 * that the kernels' arithmetic is tested on a machine without a GPU.
 *
 * Each function does the CPU driver's operations in the CPU driver's order
 * (drape-elements' truss_lanes.rs, quad_lanes.rs and spring.rs, the
 * driver's central-difference update and the slot layout's gather), with
 * no fused multiply-add (NVRTC is called with --fmad=false, the C compiler
 * with -ffp-contract=off). On the CPU the results are the driver's bit for
 * bit; on the GPU only log, expm1 and sqrt's last bits may differ.
 *
 * Arrays of 3-vectors are node-major: component k of entry i is at
 * [3*i + k] (an element reads a node's three components in one memory
 * sector). A membrane batch's reference gradients are element-minor:
 * value v of element e at [v*count + e] (neighbouring threads, neighbouring
 * addresses). A membrane batch's history is
 * value-major: value i of point p of element e, of a batch of `count`
 * elements with `stride` values per point, is at [(p*stride + i)*count + e].
 *
 * C99 and CUDA C++ both: no templates, no classes, no library calls but
 * sqrt, log, expm1, hypot, atan2, cos, sin and fabs.
 */

#ifndef DRAPE_STEP_H
#define DRAPE_STEP_H

#ifdef __CUDACC__
#define DRAPE_FN static __device__ __forceinline__
#else
#include <math.h>
#include <stddef.h>
#define DRAPE_FN static inline
#endif

/* The crimp law's series threshold (FibreLaw::TENSION_SERIES_BELOW). */
#define DRAPE_SERIES_BELOW 1e-3
/* A membrane point is degenerate where det C <= this * (tr C)^2
 * (drape_kinematics::right_stretch). */
#define DRAPE_DEGENERATE_DET_C 1e-14
/* A spring shorter than this has no direction (spring.rs). */
#define DRAPE_NO_DIRECTION 1e-12
/* The most Prony terms a step carries (the lanes' factor table). */
#define DRAPE_MAX_PRONY 8
/* The most coefficients of a shear-locking law the kernels carry. */
#define DRAPE_MAX_LOCKING 8

/* A fibre law (drape_constitutive::FibreLaw) without confinement. */
typedef struct {
    double modulus;
    double crimp_strain;
    double compression_factor;
    double buckling_stress;
} DrapeFibreLaw;

/* FibreLaw::stress. */
DRAPE_FN double drape_fibre_stress(DrapeFibreLaw law, double eps)
{
    double e = law.modulus;
    if (eps <= 0.0) {
        if (law.buckling_stress > 0.0) {
            /* FibreLaw::column at x = -eps/eps_sh. */
            double x = -eps / law.crimp_strain;
            double root = sqrt(1.0 + x);
            return -law.buckling_stress * x / (root * (1.0 + root));
        }
        double k = law.compression_factor * e;
        return k * eps;
    }
    double sh = law.crimp_strain;
    if (sh == 0.0) {
        return e * eps;
    }
    double x = eps / sh;
    if (x < DRAPE_SERIES_BELOW) {
        return e * sh * x * x * (0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x / 120.0)));
    }
    double straightened = -expm1(-x);
    return e * (eps - sh * straightened);
}

/* Truss e's two forces into slots first + 2e and first + 2e + 1, with its
 * dashpot when `dashpot` is not null (TrussBatch::forces_with_damping_into
 * at the velocities v). Returns 0, or 1 where the truss is collapsed or not
 * finite (the slots are then not written). */
DRAPE_FN int drape_truss_force(long e, DrapeFibreLaw law, const unsigned *nodes,
                               const double *length, const double *section,
                               const double *dashpot, const double *x,
                               const double *v, long n, double *slots,
                               long slot_count, long first)
{
    long i = nodes[2 * e], j = nodes[2 * e + 1];
    double d0 = x[3 * j] - x[3 * i];
    double d1 = x[3 * j + 1] - x[3 * i + 1];
    double d2 = x[3 * j + 2] - x[3 * i + 2];
    double l = sqrt(d0 * d0 + d1 * d1 + d2 * d2);
    double reference = length[e];
    /* l - l is 0 for a finite l and NaN otherwise. */
    if (!(l - l == 0.0 && reference > 0.0 && reference - reference == 0.0 &&
          l > 1e-12 * reference)) {
        return 1;
    }
    double stretch = l / reference;
    double n0 = d0 / l, n1 = d1 / l, n2 = d2 / l;
    double tau = drape_fibre_stress(law, log(stretch));
    double force = section[e] * tau / stretch;
    double f0 = n0 * force, f1 = n1 * force, f2 = n2 * force;
    double a0 = -f0, a1 = -f1, a2 = -f2;
    double b0 = f0, b1 = f1, b2 = f2;
    if (dashpot) {
        /* TrussBatch::piece_damping_into: the direction again from d. */
        if (l > 0.0) {
            double m0 = d0 / l, m1 = d1 / l, m2 = d2 / l;
            double w0 = v[3 * j] - v[3 * i];
            double w1 = v[3 * j + 1] - v[3 * i + 1];
            double w2 = v[3 * j + 2] - v[3 * i + 2];
            double c = dashpot[e] * (m0 * w0 + m1 * w1 + m2 * w2);
            double g0 = m0 * c, g1 = m1 * c, g2 = m2 * c;
            a0 -= g0;
            a1 -= g1;
            a2 -= g2;
            b0 += g0;
            b1 += g1;
            b2 += g2;
        }
    }
    long s = first + 2 * e;
    slots[3 * s] = a0;
    slots[3 * s + 1] = a1;
    slots[3 * s + 2] = a2;
    slots[3 * (s + 1)] = b0;
    slots[3 * (s + 1) + 1] = b1;
    slots[3 * (s + 1) + 2] = b2;
    return 0;
}

/* Triplet e's edges a = x_j - x_i and b = x_k - x_j and their lengths. */
DRAPE_FN void drape_bending_edges(long e, const unsigned *nodes, const double *x, double a[3],
                                  double b[3], double *la, double *lb)
{
    long i = nodes[3 * e], j = nodes[3 * e + 1], k = nodes[3 * e + 2];
    for (int c = 0; c < 3; c++) {
        a[c] = x[3 * j + c] - x[3 * i + c];
        b[c] = x[3 * k + c] - x[3 * j + c];
    }
    *la = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    *lb = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
}

/* Yarn bending triplet e, nodes (i, j, k) with j in the middle
 * (BendingBatch::element_force): E = K (p - d)/(p + d) with a = x_j - x_i,
 * b = x_k - x_j, p = |a||b|, d = a.b; its three forces into slots
 * first + 3e + 0..2. Returns 0, or 1 for a triplet with an edge of no
 * length, not finite, or folded back on itself (nothing written). */
DRAPE_FN int drape_bending_force(long e, const unsigned *nodes, const double *stiffness,
                                 const double *x, long n, double *slots, long slot_count,
                                 long first)
{
    double a[3], b[3], la, lb;
    drape_bending_edges(e, nodes, x, a, b, &la, &lb);
    if (!(la - la == 0.0 && lb - lb == 0.0 && la > 0.0 && lb > 0.0)) {
        return 1;
    }
    double p = la * lb;
    double d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    double s = p + d;
    if (s <= 5e-13 * p) {
        return 1;
    }
    double kk = stiffness[e];
    double gp = 2.0 * d / (s * s);
    double gd = -2.0 * p / (s * s);
    long at = first + 3 * e;
    for (int c = 0; c < 3; c++) {
        double da = (a[c] * (gp * lb / la) + b[c] * gd) * kk;
        double db = (b[c] * (gp * la / lb) + a[c] * gd) * kk;
        slots[3 * at + c] = -da;
        slots[3 * (at + 1) + c] = da - db;
        slots[3 * (at + 2) + c] = db;
    }
    return 0;
}

/* A resin's constants and a step's Prony factors (quad_lanes' ResinStep). */
typedef struct {
    double wave_modulus;
    double poisson;
    double shear_modulus;
    double long_term;
    double thickness;
    int prony_terms;
    /* (e^(-dt/tau_k), g_k * phi_k) per term. */
    double decay[DRAPE_MAX_PRONY];
    double weight[DRAPE_MAX_PRONY];
    /* Fibres embedded in the membrane (MembraneSection::embedded_fibres:
     * 1, else 0): each family's thickness t_f and the fibres' law. */
    double embedded;
    double fibre_thickness;
    DrapeFibreLaw fibre;
    /* The shear-locking law (resin.shear_locking) when `locking` is 1:
     * the fabric's thickness h, the odd polynomial's coefficients
     * [c1, c3, ...] (`locking_terms` of them) and, when `locking_friction`
     * is 1, the friction term's [tau_f, gamma_f]. */
    double locking;
    double fabric_thickness;
    double locking_terms;
    double locking_coefficients[DRAPE_MAX_LOCKING];
    double locking_friction;
    double friction_term[2];
} DrapeResinStep;

/* ShearLocking::stress: tau_s(gamma) (MPa). */
DRAPE_FN double drape_locking_stress(const DrapeResinStep *r, double gamma)
{
    double g2 = gamma * gamma;
    double acc = 0.0;
    for (int k = (int)r->locking_terms - 1; k >= 0; k--) {
        acc = acc * g2 + r->locking_coefficients[k];
    }
    double poly = acc * gamma;
    if (r->locking_friction != 0.0) {
        return poly + r->friction_term[0] * tanh(gamma / r->friction_term[1]);
    }
    return poly;
}

/* ShearLocking::tangent: d tau_s / d gamma (MPa). */
DRAPE_FN double drape_locking_tangent(const DrapeResinStep *r, double gamma)
{
    double g2 = gamma * gamma;
    double power = 1.0, sum = 0.0;
    for (int k = 0; k < (int)r->locking_terms; k++) {
        sum += (double)(2 * k + 1) * r->locking_coefficients[k] * power;
        power *= g2;
    }
    if (r->locking_friction != 0.0) {
        double t = tanh(gamma / r->friction_term[1]);
        return sum + r->friction_term[0] / r->friction_term[1] * (1.0 - t * t);
    }
    return sum;
}

/* The fibres of a membrane point for the shear-locking law (membrane/
 * locking.rs's kinematics): the columns of F, their unit directions u and
 * lengths, c = u1.u2 = sin gamma. Returns 0 where a fibre has collapsed
 * or the two families have closed onto each other. */
DRAPE_FN int drape_locking_fibres(const double f[3][2], double u[2][3], double len[2],
                                  double *c)
{
    for (int k = 0; k < 2; k++) {
        len[k] = sqrt(f[0][k] * f[0][k] + f[1][k] * f[1][k] + f[2][k] * f[2][k]);
    }
    if (len[0] != len[0] || len[1] != len[1] || len[0] <= 0.0 || len[1] <= 0.0) {
        return 0;
    }
    for (int k = 0; k < 2; k++) {
        for (int r = 0; r < 3; r++) {
            u[k][r] = f[r][k] / len[k];
        }
    }
    *c = u[0][0] * u[1][0] + u[0][1] * u[1][1] + u[0][2] * u[1][2];
    return !(*c != *c || fabs(*c) >= 1.0 - 5e-13);
}

/* Fibre family k's vector F N_k in a membrane point (N_k the k-th local
 * axis, onto which the gradients were turned), as
 * drape_kinematics::fibre_stretch forms it, and its length. */
DRAPE_FN double drape_fibre_vector(const double f[3][2], int k, double v[3])
{
    double n0 = k == 0 ? 1.0 : 0.0, n1 = k == 0 ? 0.0 : 1.0;
    for (int r = 0; r < 3; r++) {
        v[r] = f[r][0] * n0 + f[r][1] * n1;
    }
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

/* Point p of membrane e: its deformation gradient F (3 x 2) from the
 * element's node positions xe, and C = F^T F's C11, C12, C22, det C and
 * tr C as drape_kinematics::right_stretch forms them. Returns whether the
 * point is sound (not degenerate, finite; with `embedded` fibres, each
 * family's vector finite and longer than 1e-12 as FibreKinematics asks).
 * grad: dN/dX, value (point, node, 2) of element e at [value*count + e]. */
DRAPE_FN int drape_membrane_kinematics(long e, int nodes_per, int p, long count,
                                       const double *grad, const DrapeResinStep *resin,
                                       const double xe[4][3], double f[3][2], double c[5])
{
    const double *g = grad + (p * nodes_per * 2) * count + e;
    for (int r = 0; r < 3; r++) {
        f[r][0] = 0.0;
        f[r][1] = 0.0;
    }
    for (int a = 0; a < nodes_per; a++) {
        for (int r = 0; r < 3; r++) {
            f[r][0] += xe[a][r] * g[(2 * a) * count];
            f[r][1] += xe[a][r] * g[(2 * a + 1) * count];
        }
    }
    c[0] = f[0][0] * f[0][0] + f[1][0] * f[1][0] + f[2][0] * f[2][0];
    c[1] = f[0][0] * f[0][1] + f[1][0] * f[1][1] + f[2][0] * f[2][1];
    c[2] = f[0][1] * f[0][1] + f[1][1] * f[1][1] + f[2][1] * f[2][1];
    c[3] = c[0] * c[2] - c[1] * c[1];
    c[4] = c[0] + c[2];
    int ok = c[3] > DRAPE_DEGENERATE_DET_C * c[4] * c[4];
    for (int k = 0; resin->embedded != 0.0 && k < 2; k++) {
        double v[3];
        double length = drape_fibre_vector(f, k, v);
        /* Finite (inf - inf and NaN are not 0) and not crushed. */
        ok &= (length - length) == 0.0 && length > 1e-12;
    }
    if (resin->locking != 0.0) {
        double u[2][3], len[2], sin_gamma;
        ok &= drape_locking_fibres(f, u, len, &sin_gamma);
    }
    return ok;
}

/* Point p's response (QuadLanes::block_forces_lanes, one lane and one
 * point, which is the scalar path's arithmetic): U in closed form, the
 * rotated strain increment from the committed U, the resin's stress
 * update (its history advanced in place when `commit`), P = F U^-1 tau
 * U^-1 h_m, plus with embedded fibres t_f tau_f/lambda n (x) N_k for each
 * family and with the shear-locking law its stress
 * (MembraneBatch::point_response), and its share (P grad N_a) A of each
 * node's force into share[a]. area: point p's at [p*count + e];
 * history: value i of point p at [(p*stride + i)*count + e]. */
DRAPE_FN void drape_membrane_point(long e, int nodes_per, int p, long count,
                                   const DrapeResinStep *resin, const double *grad,
                                   const double *area, double *history, long stride,
                                   int commit, const double f[3][2], const double c[5],
                                   double share[4][3])
{
    const double *g = grad + (p * nodes_per * 2) * count + e;
    double c00 = c[0], c01 = c[1], c11 = c[2], det_c = c[3], tr_c = c[4];
    double det_u = sqrt(det_c);
    double s = sqrt(tr_c + 2.0 * det_u);
    double u00 = (c00 + det_u) / s, u01 = (c01 + 0.0) / s, u11 = (c11 + det_u) / s;
    double tr_u = u00 + u11;
    double ui00 = (tr_u - u00) / det_u, ui01 = (0.0 - u01) / det_u, ui11 = (tr_u - u11) / det_u;
    double *h = history + (p * stride) * count + e;
    double n00 = h[0], n11 = h[count], n01 = h[2 * count];
    double m00 = (n00 + u00) * 0.5, m01 = (n01 + u01) * 0.5, m11 = (n11 + u11) * 0.5;
    double det_m = m00 * m11 - m01 * m01;
    double tr_m = m00 + m11;
    double mi00 = (tr_m - m00) / det_m, mi01 = (0.0 - m01) / det_m, mi11 = (tr_m - m11) / det_m;
    double d00 = u00 - n00, d01 = u01 - n01, d11 = u11 - n11;
    double l00 = d00 * mi00 + d01 * mi01;
    double l01 = d00 * mi01 + d01 * mi11;
    double l10 = d01 * mi00 + d11 * mi01;
    double l11 = d01 * mi01 + d11 * mi11;
    double e00 = (l00 + l00) * 0.5;
    double e11 = (l11 + l11) * 0.5;
    double e01 = (l01 + l10) * 0.5;
    double e10 = (l10 + l01) * 0.5;
    double k = resin->wave_modulus, nu = resin->poisson;
    double t00 = h[3 * count] + k * (e00 + nu * e11);
    double t11 = h[4 * count] + k * (nu * e00 + e11);
    double d_s0 = resin->shear_modulus * (e01 + e10);
    double t01;
    if (resin->prony_terms == 0) {
        t01 = h[5 * count] + d_s0;
    } else {
        double s0 = h[6 * count] + d_s0;
        double relaxing = 0.0;
        for (int q = 0; q < resin->prony_terms; q++) {
            double qk = resin->decay[q] * h[(7 + q) * count] + resin->weight[q] * d_s0;
            relaxing += qk;
            if (commit) {
                h[(7 + q) * count] = qk;
            }
        }
        if (commit) {
            h[6 * count] = s0;
        }
        t01 = resin->long_term * s0 + relaxing;
    }
    if (commit) {
        h[0] = u00;
        h[count] = u11;
        h[2 * count] = u01;
        h[3 * count] = t00;
        h[4 * count] = t11;
        h[5 * count] = t01;
    }
    double a00 = ui00 * t00 + ui01 * t01;
    double a01 = ui00 * t01 + ui01 * t11;
    double a10 = ui01 * t00 + ui11 * t01;
    double a11 = ui01 * t01 + ui11 * t11;
    double b00 = a00 * ui00 + a01 * ui01;
    double b01 = a00 * ui01 + a01 * ui11;
    double b10 = a10 * ui00 + a11 * ui01;
    double b11 = a10 * ui01 + a11 * ui11;
    double h_m = resin->thickness;
    double piola[3][2];
    for (int r = 0; r < 3; r++) {
        piola[r][0] = (f[r][0] * b00 + f[r][1] * b10) * h_m;
        piola[r][1] = (f[r][0] * b01 + f[r][1] * b11) * h_m;
    }
    for (int q = 0; resin->embedded != 0.0 && q < 2; q++) {
        double v[3];
        double length = drape_fibre_vector(f, q, v);
        double stretch = length / 1.0;
        double tau_f = drape_fibre_stress(resin->fibre, log(stretch));
        double scale = resin->fibre_thickness * tau_f / stretch;
        for (int r = 0; r < 3; r++) {
            piola[r][q] += v[r] / length * scale;
        }
    }
    if (resin->locking != 0.0) {
        /* LockingPoint::add_stress: dW/da_k = phi g_k, phi = h tau_s /
         * cos gamma, g_k = (u_other - c u_k)/|a_k|. The point passed
         * drape_membrane_kinematics, so its fibres are sound. */
        double u[2][3], len[2], c = 0.0;
        drape_locking_fibres(f, u, len, &c);
        double gamma = asin(c);
        double cos_gamma = sqrt(1.0 - c * c);
        double phi = resin->fabric_thickness * drape_locking_stress(resin, gamma) / cos_gamma;
        for (int k = 0; k < 2; k++) {
            for (int r = 0; r < 3; r++) {
                piola[r][k] += (u[1 - k][r] - u[k][r] * c) / len[k] * phi;
            }
        }
    }
    double w = area[p * count + e];
    for (int a = 0; a < nodes_per; a++) {
        for (int r = 0; r < 3; r++) {
            share[a][r] = (piola[r][0] * g[(2 * a) * count] + piola[r][1] * g[(2 * a + 1) * count]) * w;
        }
    }
}

/* The node positions of membrane e. */
DRAPE_FN void drape_membrane_nodes(long e, int nodes_per, const unsigned *nodes,
                                   const double *x, double xe[4][3])
{
    for (int a = 0; a < nodes_per; a++) {
        long i = nodes[nodes_per * e + a];
        xe[a][0] = x[3 * i];
        xe[a][1] = x[3 * i + 1];
        xe[a][2] = x[3 * i + 2];
    }
}

/* Resin-only membrane e of `nodes_per` nodes and `points` integration
 * points (quads 4 and 4, triangles 3 and 1), its points one after another:
 * its forces (each node's shares summed from zero in point order) into
 * slots first + nodes_per*e + a, its history advanced in place when
 * `commit` (else read only, as a force evaluation from the committed
 * history). Returns 0, or 1 where a point is degenerate or not finite
 * (nothing written). */
DRAPE_FN int drape_membrane_force(long e, int nodes_per, int points, long count,
                                  const DrapeResinStep *resin, const unsigned *nodes,
                                  const double *grad, const double *area, double *history,
                                  long stride, int commit, const double *x, long n,
                                  double *slots, long slot_count, long first)
{
    double xe[4][3];
    drape_membrane_nodes(e, nodes_per, nodes, x, xe);
    double f[4][3][2];
    double c[4][5];
    int ok = 1;
    for (int p = 0; p < points; p++) {
        ok &= drape_membrane_kinematics(e, nodes_per, p, count, grad, resin, xe, f[p], c[p]);
    }
    if (!ok) {
        return 1;
    }
    double force[4][3];
    for (int a = 0; a < 4; a++) {
        force[a][0] = 0.0;
        force[a][1] = 0.0;
        force[a][2] = 0.0;
    }
    for (int p = 0; p < points; p++) {
        double share[4][3];
        drape_membrane_point(e, nodes_per, p, count, resin, grad, area, history, stride, commit,
                             f[p], c[p], share);
        for (int a = 0; a < nodes_per; a++) {
            for (int r = 0; r < 3; r++) {
                force[a][r] += share[a][r];
            }
        }
    }
    for (int a = 0; a < nodes_per; a++) {
        long s = first + nodes_per * e + a;
        slots[3 * s] = force[a][0];
        slots[3 * s + 1] = force[a][1];
        slots[3 * s + 2] = force[a][2];
    }
    return 0;
}

/* A quad (4 nodes, 2 x 2 points) and a triangle (3 nodes, 1 point), the
 * counts constant so that the loops unroll. */
DRAPE_FN int drape_quad_force(long e, long count, const DrapeResinStep *resin,
                              const unsigned *nodes, const double *grad, const double *area,
                              double *history, long stride, int commit, const double *x,
                              long n, double *slots, long slot_count, long first)
{
    return drape_membrane_force(e, 4, 4, count, resin, nodes, grad, area, history, stride,
                                commit, x, n, slots, slot_count, first);
}

DRAPE_FN int drape_triangle_force(long e, long count, const DrapeResinStep *resin,
                                  const unsigned *nodes, const double *grad,
                                  const double *area, double *history, long stride,
                                  int commit, const double *x, long n, double *slots,
                                  long slot_count, long first)
{
    return drape_membrane_force(e, 3, 1, count, resin, nodes, grad, area, history, stride,
                                commit, x, n, slots, slot_count, first);
}

/* ForceTable::force_and_stiffness's force: F(delta) of the piecewise
 * linear table of `len` points (ext, frc), its end segments extended. */
DRAPE_FN double drape_spring_table(const double *ext, const double *frc, long len, double delta)
{
    /* ForceTable::segment: how many of ext[1..=len-2] are <= delta. */
    long seg = 0;
    for (long k = 1; k <= len - 2; k++) {
        seg += ext[k] <= delta;
    }
    double slope = (frc[seg + 1] - frc[seg]) / (ext[seg + 1] - ext[seg]);
    return frc[seg] + slope * (delta - ext[seg]);
}

/* Spring e's force on its node into slot first + e (SpringBatch::
 * element_force): F(|x - anchor| - L0) along the anchor-to-node direction.
 * table: the (extension, force) points from table_start[e] to
 * table_start[e] + table_len[e]. */
DRAPE_FN void drape_spring_force(long e, const unsigned *nodes, const double *anchor,
                                 const double *rest, const long *table_start,
                                 const long *table_len, const double *extension,
                                 const double *table_force, long springs,
                                 const double *x, long n, double *slots,
                                 long slot_count, long first)
{
    long i = nodes[e];
    double d0 = x[3 * i] - anchor[3 * e];
    double d1 = x[3 * i + 1] - anchor[3 * e + 1];
    double d2 = x[3 * i + 2] - anchor[3 * e + 2];
    double l = sqrt(d0 * d0 + d1 * d1 + d2 * d2);
    double s0 = 0.0, s1 = 0.0, s2 = 0.0;
    if (l > DRAPE_NO_DIRECTION) {
        double n0 = d0 / l, n1 = d1 / l, n2 = d2 / l;
        double delta = l - rest[e];
        double force = drape_spring_table(extension + table_start[e],
                                          table_force + table_start[e], table_len[e], delta);
        s0 = n0 * force;
        s1 = n1 * force;
        s2 = n2 * force;
    }
    long s = first + e;
    slots[3 * s] = s0;
    slots[3 * s + 1] = s1;
    slots[3 * s + 2] = s2;
}

/* Node i's internal force: its slots summed in the layout's order
 * (SlotLayout::gather). */
DRAPE_FN void drape_gather(long i, const long *ptr, const unsigned *node_slots,
                           const double *slots, long slot_count, double *f_int,
                           long n)
{
    double s0 = 0.0, s1 = 0.0, s2 = 0.0;
    for (long k = ptr[i]; k < ptr[i + 1]; k++) {
        long s = node_slots[k];
        s0 += slots[3 * s];
        s1 += slots[3 * s + 1];
        s2 += slots[3 * s + 2];
    }
    f_int[3 * i] = s0;
    f_int[3 * i + 1] = s1;
    f_int[3 * i + 2] = s2;
}

/* Where a constrained component k of node i (bit k of fixed[i]) is at
 * the end of the step: at its reference coordinate, or, where a boundary
 * motion moves it (bit 3 + k), at the step's prescribed coordinate
 * held[moving[i] + the node's moving components before k]
 * (drape_time::PrescribedMotions, in node and component order). */
DRAPE_FN double drape_held(long i, int k, const unsigned char *fixed, const double *x0,
                           const int *moving, const double *held)
{
    unsigned f = fixed[i];
    if (f & (8u << k)) {
        long j = moving[i];
        for (int c = 0; c < k; c++) {
            j += (f >> (3 + c)) & 1u;
        }
        return held[j];
    }
    return x0[3 * i + k] + 0.0;
}

/* Node i's central-difference update (Explicit's step): velocity to n+1/2
 * with mass-proportional damping at the mid-step velocity, position to
 * n+1; a constrained component where drape_held puts it. f_ext: the
 * node's external force at step n. */
DRAPE_FN void drape_update(long i, long n, const double *x, const double *v,
                           const double f_ext[3], const double *f_int,
                           const double *mass, const unsigned char *fixed,
                           const double *x0, const int *moving, const double *held,
                           double c1, double c2, double dt_avg, double h, double *x_new,
                           double *v_new)
{
    double m = mass[i];
    for (int k = 0; k < 3; k++) {
        long at = 3 * i + k;
        double a = (f_ext[k] - f_int[at]) / m;
        double vn = (v[at] * c1 + a * dt_avg) * c2;
        double xn = x[at] + vn * h;
        if (fixed[i] & (1 << k)) {
            xn = drape_held(i, k, fixed, x0, moving, held);
            vn = (xn - x[at]) / h;
        }
        v_new[at] = vn;
        x_new[at] = xn;
    }
}

/* ---- Contact with one rigid tool (drape-contact's explicit pass for a
 * node against a single tool moved by a prescribed displacement: the
 * forward-increment multiplier in closed form, then Coulomb friction by
 * the return mapping; crates/contact/src/explicit.rs, surface.rs). ---- */

/* A tool as the kernels read it, doubles at these indices. */
#define DRAPE_TOOL_KIND 0      /* 0 plane, 1 sphere, 2 surface of revolution */
#define DRAPE_TOOL_POINT 1     /* 3: plane point, sphere centre, axis origin */
#define DRAPE_TOOL_NORMAL 4    /* 3: plane normal */
#define DRAPE_TOOL_RADIUS 7    /* sphere radius */
#define DRAPE_TOOL_FREE 8      /* 2: the profile's free start and end (0/1) */
#define DRAPE_TOOL_AXIS 10     /* 3: direction of motion */
#define DRAPE_TOOL_FRICTION 13 /* Coulomb mu */
#define DRAPE_TOOL_OFFSET 14   /* the fabric's mid-surface offset */
#define DRAPE_TOOL_SLACK 15    /* the contact guard's fault tolerance */
#define DRAPE_TOOL_TRAVEL 16   /* the contact guard's largest travel */
#define DRAPE_TOOL_SEGMENTS 17 /* number of profile segments */
#define DRAPE_TOOL_PROFILE 18  /* 6 per segment: kind (0 line, 1 arc), then
                                  line: from r, z, to r, z;
                                  arc: centre r, z, radius, from, to (deg) */
#define DRAPE_PI 3.14159265358979323846
#define DRAPE_TAU 6.28318530717958647692

/* Per step, the update's [c1, c2, dt_avg, h] and the tool's displacement
 * after and before the step, its velocity, tau = dt_avg/(1 +
 * damping*dt_avg/2), the step before (0 at a run's first) and the
 * mass-proportional damping alpha. */
#define DRAPE_PARAMS 10

/* Each node's running sums over the steps, doubles [k*n + i] for these k:
 * the works of the internal, external, damping, boundary and contact
 * forces, the friction dissipated, and the impulse of the normal contact
 * force along the tool's axis; then (k = 7, not summed) that force at the
 * last step. */
#define DRAPE_SUMS 8
/* A node's contact status (drape_contact::ContactStatus). */
#define DRAPE_OPEN 0
#define DRAPE_STICK 1
#define DRAPE_SLIP 2
/* drape_contact::TOUCHING: within this fraction of the offset a node
 * rests on a tool. */
#define DRAPE_TOUCHING 1e-6

/* ProfileSegment::closest: the closest point (pr, pz) of segment `seg` to
 * (qr, qz), the left normal (nr, nz), and 0 inside, 1 at the start, 2 at
 * the end. */
DRAPE_FN int drape_segment_closest(const double *seg, double qr, double qz, double *pr,
                                   double *pz, double *nr, double *nz)
{
    if (seg[0] == 0.0) {
        double ar = seg[1], az = seg[2], br = seg[3], bz = seg[4];
        double tr = br - ar, tz = bz - az;
        double s = ((qr - ar) * tr + (qz - az) * tz) / (tr * tr + tz * tz);
        double len = sqrt(tz * tz + tr * tr);
        *nr = -tz / len;
        *nz = tr / len;
        if (s <= 0.0) {
            *pr = ar;
            *pz = az;
            return 1;
        }
        if (s >= 1.0) {
            *pr = br;
            *pz = bz;
            return 2;
        }
        *pr = ar + tr * s;
        *pz = az + tz * s;
        return 0;
    }
    double cr = seg[1], cz = seg[2], radius = seg[3];
    double a0 = seg[4] * (DRAPE_PI / 180.0), a1 = seg[5] * (DRAPE_PI / 180.0);
    double dr = qr - cr, dz = qz - cz;
    double lo = a0 < a1 ? a0 : a1;
    double hi = a0 < a1 ? a1 : a0;
    double a = atan2(dz, dr);
    while (a < lo) {
        a += DRAPE_TAU;
    }
    while (a >= lo + DRAPE_TAU) {
        a -= DRAPE_TAU;
    }
    int clamp = 0;
    if (a <= hi) {
        clamp = 0;
    } else if (a - hi < lo + DRAPE_TAU - a) {
        a = hi;
        clamp = (a1 > a0) ? 2 : 1; /* at hi: the end when counter-clockwise */
    } else {
        a = lo;
        clamp = (a1 > a0) ? 1 : 2;
    }
    double er = cos(a), ez = sin(a);
    if (a1 > a0) {
        *nr = -er;
        *nz = -ez;
    } else {
        *nr = er;
        *nz = ez;
    }
    *pr = cr + er * radius;
    *pz = cz + ez * radius;
    return clamp;
}

/* Tool::project of the point (x0, x1, x2) with the tool displaced by u:
 * the signed gap (the surface's own) and the outward normal. */
DRAPE_FN double drape_tool_project(const double *tool, double u, double x0, double x1,
                                   double x2, double *normal)
{
    const double *axis = tool + DRAPE_TOOL_AXIS;
    double q0 = x0 - axis[0] * u, q1 = x1 - axis[1] * u, q2 = x2 - axis[2] * u;
    const double *o = tool + DRAPE_TOOL_POINT;
    int kind = (int)tool[DRAPE_TOOL_KIND];
    if (kind == 0) {
        const double *n = tool + DRAPE_TOOL_NORMAL;
        normal[0] = n[0];
        normal[1] = n[1];
        normal[2] = n[2];
        return (q0 - o[0]) * n[0] + (q1 - o[1]) * n[1] + (q2 - o[2]) * n[2];
    }
    double d0 = q0 - o[0], d1 = q1 - o[1], d2 = q2 - o[2];
    if (kind == 1) {
        double r = sqrt(d0 * d0 + d1 * d1 + d2 * d2);
        if (r > 0.0) {
            normal[0] = d0 / r;
            normal[1] = d1 / r;
            normal[2] = d2 / r;
        } else {
            normal[0] = 0.0;
            normal[1] = 0.0;
            normal[2] = 1.0;
        }
        return r - tool[DRAPE_TOOL_RADIUS];
    }
    double r = hypot(d0, d1);
    double e0 = 1.0, e1 = 0.0;
    if (r > 0.0) {
        e0 = d0 / r;
        e1 = d1 / r;
    }
    int segments = (int)tool[DRAPE_TOOL_SEGMENTS];
    double best_r = 0.0, best_z = 0.0, best_nr = 0.0, best_nz = 0.0, best_d2 = 1.0 / 0.0;
    int at_free_end = 0;
    for (int k = 0; k < segments; k++) {
        double pr, pz, nr, nz;
        int clamp = drape_segment_closest(tool + DRAPE_TOOL_PROFILE + 6 * k, r, d2, &pr, &pz,
                                          &nr, &nz);
        double vr = r - pr, vz = d2 - pz;
        double dd = vr * vr + vz * vz;
        if (dd < best_d2) {
            best_r = pr;
            best_z = pz;
            best_nr = nr;
            best_nz = nz;
            best_d2 = dd;
            at_free_end = (k == 0 && clamp == 1 && tool[DRAPE_TOOL_FREE] != 0.0) ||
                          (k == segments - 1 && clamp == 2 && tool[DRAPE_TOOL_FREE + 1] != 0.0);
        }
    }
    double vr = r - best_r, vz = d2 - best_z;
    double dist = sqrt(vr * vr + vz * vz);
    double sign = (at_free_end || vr * best_nr + vz * best_nz >= 0.0) ? 1.0 : -1.0;
    double n2r = best_nr, n2z = best_nz;
    if (dist > 1e-12) {
        n2r = vr / dist * sign;
        n2z = vz / dist * sign;
    }
    normal[0] = e0 * n2r + 0.0 * n2z;
    normal[1] = e1 * n2r + 0.0 * n2z;
    normal[2] = 0.0 * n2r + 1.0 * n2z;
    return sign * dist;
}

/* Node i's contact with the tool after the update (ExplicitContact::
 * enforce_step with one tool): a node inside it is put back on it by its
 * multiplier, then friction on its tangential velocity relative to the
 * tool; its force into contact_force (0 when free). Returns 0, 1 for a
 * node that travelled more than the guard's limit, 2 for a gap that
 * jumped more than the step explains (ContactFault: nothing corrected). */
DRAPE_FN int drape_contact(long i, long n, const double *tool, const double *params,
                           const double *mass, const unsigned char *fixed,
                           const double *x0, const int *moving, const double *held,
                           const double *x_old, double *x,
                           double *v, double *contact_force, unsigned char *status,
                           double *sums)
{
    contact_force[3 * i] = 0.0;
    contact_force[3 * i + 1] = 0.0;
    contact_force[3 * i + 2] = 0.0;
    status[i] = DRAPE_OPEN;
    sums[7 * n + i] = 0.0;
    if ((fixed[i] & 7u) == 7u) {
        return 0;
    }
    double h = params[3], u = params[4], u_before = params[5], v_tool = params[6];
    double tau = params[7];
    double xi0 = x[3 * i], xi1 = x[3 * i + 1], xi2 = x[3 * i + 2];
    double nrm[3];
    double gap = drape_tool_project(tool, u, xi0, xi1, xi2, nrm) - tool[DRAPE_TOOL_OFFSET];
    if (!(gap < 0.0)) {
        if (gap <= DRAPE_TOUCHING * tool[DRAPE_TOOL_OFFSET]) {
            status[i] = DRAPE_STICK;
        }
        return 0;
    }
    const double *axis = tool + DRAPE_TOOL_AXIS;
    double vi0 = v[3 * i], vi1 = v[3 * i + 1], vi2 = v[3 * i + 2];
    double node_travel = sqrt(vi0 * vi0 + vi1 * vi1 + vi2 * vi2) * h;
    double axis_len = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    double tool_travel = fabs(u - u_before) * axis_len;
    double travel = node_travel + tool_travel;
    double slack = tool[DRAPE_TOOL_SLACK];
    if (travel > tool[DRAPE_TOOL_TRAVEL]) {
        return 1;
    }
    if (-gap > travel + slack) {
        double before[3] = {xi0 - vi0 * h, xi1 - vi1 * h, xi2 - vi2 * h};
        double unused[3];
        double previous = drape_tool_project(tool, u_before, before[0], before[1], before[2],
                                             unused) -
                          tool[DRAPE_TOOL_OFFSET];
        if (previous - gap > travel + slack) {
            return 2;
        }
    }
    double m = mass[i];
    double mu = -gap * m;
    if (!(mu > 0.0)) {
        mu = 0.0;
    }
    double xs[3] = {xi0, xi1, xi2};
    double vs[3] = {vi0, vi1, vi2};
    double f[3];
    double lambda_scale = 1.0 / (h * tau);
    double lambda = mu * lambda_scale;
    for (int k = 0; k < 3; k++) {
        double dx = nrm[k] * (mu / m);
        xs[k] += dx;
        vs[k] += dx / h;
        f[k] = 0.0 + nrm[k] * lambda;
    }
    status[i] = DRAPE_STICK;
    /* The tool's force on the fabric along its axis (its magnitude for a
     * tool that does not move), over the step. */
    double along = lambda;
    if (axis[0] != 0.0 || axis[1] != 0.0 || axis[2] != 0.0) {
        along = (nrm[0] * axis[0] + nrm[1] * axis[1] + nrm[2] * axis[2]) * lambda;
    }
    sums[6 * n + i] += along * h;
    sums[7 * n + i] = along;
    double friction = tool[DRAPE_TOOL_FRICTION];
    double ft[3] = {0.0, 0.0, 0.0};
    int slid = 0;
    if (friction != 0.0 && mu > 0.0) {
        double rel[3], vt[3];
        for (int k = 0; k < 3; k++) {
            rel[k] = vs[k] - axis[k] * v_tool;
        }
        double dot = nrm[0] * rel[0] + nrm[1] * rel[1] + nrm[2] * rel[2];
        for (int k = 0; k < 3; k++) {
            vt[k] = rel[k] - nrm[k] * dot;
        }
        double speed = sqrt(vt[0] * vt[0] + vt[1] * vt[1] + vt[2] * vt[2]);
        if (speed != 0.0) {
            double slide_lambda = mu / (h * tau);
            double trial = m * speed / tau;
            double limit = friction * slide_lambda;
            double magnitude = trial <= limit ? trial : limit;
            status[i] = trial <= limit ? DRAPE_STICK : DRAPE_SLIP;
            for (int k = 0; k < 3; k++) {
                ft[k] = -vt[k] / speed * magnitude;
                double dv = ft[k] * (tau / m);
                vs[k] += dv;
                xs[k] += dv * h;
                f[k] += ft[k];
            }
            slid = 1;
        }
    }
    if (slid) {
        /* What the friction force does against the slip left after it. */
        double rel[3];
        for (int k = 0; k < 3; k++) {
            rel[k] = vs[k] - axis[k] * v_tool;
        }
        double dot = nrm[0] * rel[0] + nrm[1] * rel[1] + nrm[2] * rel[2];
        double w = 0.0;
        for (int k = 0; k < 3; k++) {
            w += ft[k] * (rel[k] - nrm[k] * dot);
        }
        sums[5 * n + i] -= w * h;
    }
    for (int k = 0; k < 3; k++) {
        long at = 3 * i + k;
        /* A partly constrained node keeps its prescribed components. */
        if (fixed[i] & (1 << k)) {
            xs[k] = drape_held(i, k, fixed, x0, moving, held);
            vs[k] = (xs[k] - x_old[at]) / h;
        }
        x[at] = xs[k];
        v[at] = vs[k];
        contact_force[at] = f[k];
    }
    return 0;
}

/* Node i's works over the step (Explicit's step: the centred increment
 * dx = v_n-1/2 * dt_prev/2 + (x_n+1 - x_n)/2 at the forces of step n),
 * added to its running sums. x, v: step n's; x_new, v_new: n+1's after
 * the contact; f_int, f_ext: step n's; contact_force: this step's. */
DRAPE_FN void drape_works(long i, long n, const double *params, const double *mass,
                          const unsigned char *fixed, const double *x, const double *v,
                          const double *x_new, const double *v_new, const double *f_int,
                          const double f_ext[3], const double *contact_force, double *sums)
{
    double dt_avg = params[2], dt_prev = params[8], damping = params[9];
    double m = mass[i];
    double w_int = 0.0, w_ext = 0.0, w_damp = 0.0, w_bc = 0.0, w_c = 0.0;
    for (int k = 0; k < 3; k++) {
        long at = 3 * i + k;
        double dx = v[at] * (0.5 * dt_prev) + (x_new[at] - x[at]) * 0.5;
        double v_mid = (v[at] + v_new[at]) * 0.5;
        double damp = (v[at] + v_new[at]) * 0.5 * (damping * m);
        if ((fixed[i] & (1 << k)) && dt_avg > 0.0) {
            double inertia = (v_new[at] - v[at]) * (m / dt_avg);
            double r = inertia - (f_ext[k] - f_int[at] - damp + contact_force[at]);
            double dx_inertia = dt_prev > 0.0 ? dx : v_mid * dt_avg;
            w_bc += r * dx + inertia * (dx_inertia - dx);
        }
        w_int += f_int[at] * dx;
        w_ext += f_ext[k] * dx;
        w_damp += damp * dx;
        w_c += contact_force[at] * dx;
    }
    sums[i] += w_int;
    sums[n + i] += w_ext;
    sums[2 * n + i] += w_damp;
    sums[3 * n + i] += w_bc;
    sums[4 * n + i] += w_c;
}

/* The follower pressures on node i at positions x (drape_time::
 * PressurePass::add_into): each of its slots' p a(t) A/k, the vector area
 * A of the slot's element (pressure::vector_area), summed from zero in
 * slot order. Slot s: its element's k nodes at p_nodes[4s..4s + k]
 * (k = p_count[s]), its load's p a(t) at scales[p_load[s]]. */
DRAPE_FN void drape_pressure(long i, const long *p_ptr, const unsigned *p_slot,
                             const unsigned *p_nodes, const unsigned char *p_count,
                             const unsigned *p_load, const double *scales, const double *x,
                             double sum[3])
{
    sum[0] = 0.0;
    sum[1] = 0.0;
    sum[2] = 0.0;
    for (long q = p_ptr[i]; q < p_ptr[i + 1]; q++) {
        long s = p_slot[q];
        const unsigned *e = p_nodes + 4 * s;
        int k = p_count[s];
        double a[3], b[3];
        for (int c = 0; c < 3; c++) {
            if (k == 4) {
                a[c] = x[3 * (long)e[2] + c] - x[3 * (long)e[0] + c];
                b[c] = x[3 * (long)e[3] + c] - x[3 * (long)e[1] + c];
            } else {
                a[c] = x[3 * (long)e[1] + c] - x[3 * (long)e[0] + c];
                b[c] = x[3 * (long)e[2] + c] - x[3 * (long)e[0] + c];
            }
        }
        double cross[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                           a[0] * b[1] - a[1] * b[0]};
        double scale = scales[p_load[s]] / (double)k;
        for (int c = 0; c < 3; c++) {
            sum[c] += 0.5 * cross[c] * scale;
        }
    }
}

/* Node i's whole step: the update, the contact when there is a tool
 * (`tool` not null), the works. `held`: the step's prescribed coordinates
 * (drape_held); `weight`: each node's weight; `loads` (null for none):
 * each nodal load's force at the step's start, node i's loads
 * load_of[load_ptr[i] .. load_ptr[i + 1]]; `scales` (null for none): each
 * pressure's p a(t) at the step's start, node i's pressure slots as
 * drape_pressure reads them. The external force is drape_time::
 * external_forces' (the weight, then the loads in their order) plus the
 * pressures' sum. Returns the contact's fault (0: none). */
DRAPE_FN int drape_node_step(long i, long n, const double *params, const double *x,
                             const double *v, const double *weight, const long *load_ptr,
                             const unsigned *load_of, const double *loads, const long *p_ptr,
                             const unsigned *p_slot, const unsigned *p_nodes,
                             const unsigned char *p_count, const unsigned *p_load,
                             const double *scales, const double *f_int, const double *mass,
                             const unsigned char *fixed, const double *x0, const int *moving,
                             const double *held, const double *tool, double *x_new,
                             double *v_new, double *contact_force, unsigned char *status,
                             double *sums)
{
    double f_ext[3] = {weight[3 * i], weight[3 * i + 1], weight[3 * i + 2]};
    if (loads) {
        for (long q = load_ptr[i]; q < load_ptr[i + 1]; q++) {
            long l = load_of[q];
            f_ext[0] += loads[3 * l];
            f_ext[1] += loads[3 * l + 1];
            f_ext[2] += loads[3 * l + 2];
        }
    }
    if (scales) {
        double sum[3];
        drape_pressure(i, p_ptr, p_slot, p_nodes, p_count, p_load, scales, x, sum);
        f_ext[0] += sum[0];
        f_ext[1] += sum[1];
        f_ext[2] += sum[2];
    }
    drape_update(i, n, x, v, f_ext, f_int, mass, fixed, x0, moving, held, params[0], params[1],
                 params[2], params[3], x_new, v_new);
    int fault = 0;
    if (tool) {
        fault = drape_contact(i, n, tool, params, mass, fixed, x0, moving, held, x, x_new,
                              v_new, contact_force, status, sums);
    }
    if (fault == 0) {
        drape_works(i, n, params, mass, fixed, x, v, x_new, v_new, f_int, f_ext,
                    contact_force, sums);
    }
    return fault;
}

/* ---- The stable step (Explicit::estimated_time_step): each element's,
 * the smallest of a batch into its slot by an integer minimum on the
 * bits (positive doubles order as their bits), the same whatever the
 * order. ---- */

/* TrussBatch::element_stable_time_step with the nodes' mass shares. */
DRAPE_FN double drape_truss_step(long e, double wave_modulus, const unsigned *nodes,
                                 const double *section, const double *share, const double *x,
                                 long n)
{
    long i = nodes[2 * e], j = nodes[2 * e + 1];
    double d0 = x[3 * j] - x[3 * i], d1 = x[3 * j + 1] - x[3 * i + 1], d2 = x[3 * j + 2] - x[3 * i + 2];
    double l = sqrt(d0 * d0 + d1 * d1 + d2 * d2);
    double k = wave_modulus * section[e] / l;
    return 2.0 / sqrt(k * (1.0 / share[2 * e] + 1.0 / share[2 * e + 1]));
}

/* BendingBatch::element_stable_time_step. */
DRAPE_FN double drape_bending_step(long e, const unsigned *nodes, const double *stiffness,
                                   const double *share, const double *x, long n)
{
    double a[3], b[3], la, lb;
    drape_bending_edges(e, nodes, x, a, b, &la, &lb);
    double ga = 1.0 / la, gb = 1.0 / lb;
    double sum = ga * ga / share[3 * e] + (ga + gb) * (ga + gb) / share[3 * e + 1] +
                 gb * gb / share[3 * e + 2];
    return 2.0 / sqrt(0.5 * stiffness[e] * sum);
}

/* SpringBatch::element_stable_time_step with the node's mass. */
DRAPE_FN double drape_spring_step(long e, const unsigned *nodes, const double *anchor,
                                  const double *rest, const long *table_start,
                                  const long *table_len, const double *extension,
                                  const double *table_force, double max_stiffness,
                                  long springs, const double *mass, const double *x, long n)
{
    long i = nodes[e];
    double d0 = x[3 * i] - anchor[3 * e];
    double d1 = x[3 * i + 1] - anchor[3 * e + 1];
    double d2 = x[3 * i + 2] - anchor[3 * e + 2];
    double l = sqrt(d0 * d0 + d1 * d1 + d2 * d2);
    double delta = l - rest[e];
    double f = drape_spring_table(extension + table_start[e], table_force + table_start[e],
                                  table_len[e], delta);
    double k = fabs(f) / l;
    /* f64::max: the other where one is NaN. */
    if (!(k >= max_stiffness)) {
        k = max_stiffness;
    }
    if (k > 0.0) {
        return 2.0 * sqrt(mass[i] / k);
    }
    return 1.0 / 0.0;
}

/* A membrane's stable step (MembraneBatch::element_stable_time_step,
 * kappa its stiffness bound; QuadLanes::block_stable_steps one lane):
 * the Laplacian of its current shape's gradients, Gershgorin's bound on
 * its mass-weighted eigenvalue; 0 for a degenerate or non-finite point.
 * With the shear-locking law, kappa stiffened by 2 h tau_s' at the
 * element's largest shear (F from the reference gradients `grad`). */
DRAPE_FN double drape_membrane_step(long e, long count, int nodes_per, int points,
                                    const unsigned *nodes, const double *nodal_area,
                                    const DrapeResinStep *resin, const double *grad,
                                    double kappa, double rho_h, const double *x, long n)
{
    double xe[4][3];
    for (int a = 0; a < nodes_per; a++) {
        long i = nodes[nodes_per * e + a];
        xe[a][0] = x[3 * i];
        xe[a][1] = x[3 * i + 1];
        xe[a][2] = x[3 * i + 2];
    }
    double lap[4][4];
    for (int a = 0; a < 4; a++) {
        for (int b = 0; b < 4; b++) {
            lap[a][b] = 0.0;
        }
    }
    for (int p = 0; p < points; p++) {
        double d_xi[4], d_eta[4], weight;
        if (nodes_per == 3) {
            d_xi[0] = -1.0, d_xi[1] = 1.0, d_xi[2] = 0.0;
            d_eta[0] = -1.0, d_eta[1] = 0.0, d_eta[2] = 1.0;
            weight = 0.5;
        } else {
            const double gauss = 0.5773502691896258;
            double xi = (p == 0 || p == 3) ? -gauss : gauss;
            double eta = (p < 2) ? -gauss : gauss;
            double xm = 1.0 - xi, xp = 1.0 + xi, em = 1.0 - eta, ep = 1.0 + eta;
            d_xi[0] = -0.25 * em, d_xi[1] = 0.25 * em, d_xi[2] = 0.25 * ep, d_xi[3] = -0.25 * ep;
            d_eta[0] = -0.25 * xm, d_eta[1] = -0.25 * xp, d_eta[2] = 0.25 * xp;
            d_eta[3] = 0.25 * xm;
            weight = 1.0;
        }
        double g1[3] = {0.0, 0.0, 0.0}, g2[3] = {0.0, 0.0, 0.0};
        for (int a = 0; a < nodes_per; a++) {
            for (int c = 0; c < 3; c++) {
                g1[c] += xe[a][c] * d_xi[a];
                g2[c] += xe[a][c] * d_eta[a];
            }
        }
        double nv[3] = {g1[1] * g2[2] - g1[2] * g2[1], g1[2] * g2[0] - g1[0] * g2[2],
                        g1[0] * g2[1] - g1[1] * g2[0]};
        double size = sqrt(nv[0] * nv[0] + nv[1] * nv[1] + nv[2] * nv[2]);
        double n1 = sqrt(g1[0] * g1[0] + g1[1] * g1[1] + g1[2] * g1[2]);
        double n2 = sqrt(g2[0] * g2[0] + g2[1] * g2[1] + g2[2] * g2[2]);
        if (!(size - size == 0.0) || size <= 1e-12 * n1 * n2) {
            return 0.0;
        }
        double normal[3] = {nv[0] / size, nv[1] / size, nv[2] / size};
        double e1[3] = {g1[0] / n1, g1[1] / n1, g1[2] / n1};
        double e2[3] = {normal[1] * e1[2] - normal[2] * e1[1],
                        normal[2] * e1[0] - normal[0] * e1[2],
                        normal[0] * e1[1] - normal[1] * e1[0]};
        double j00 = e1[0] * g1[0] + e1[1] * g1[1] + e1[2] * g1[2];
        double j10 = e2[0] * g1[0] + e2[1] * g1[1] + e2[2] * g1[2];
        double j01 = e1[0] * g2[0] + e1[1] * g2[1] + e1[2] * g2[2];
        double j11 = e2[0] * g2[0] + e2[1] * g2[1] + e2[2] * g2[2];
        double det_j = j00 * j11 - j10 * j01;
        double t00 = j11 / det_j, t01 = -j10 / det_j, t10 = -j01 / det_j, t11 = j00 / det_j;
        double grad[4][2];
        for (int a = 0; a < nodes_per; a++) {
            grad[a][0] = t00 * d_xi[a] + t01 * d_eta[a];
            grad[a][1] = t10 * d_xi[a] + t11 * d_eta[a];
        }
        double area = det_j * weight;
        for (int a = 0; a < nodes_per; a++) {
            for (int b = a; b < nodes_per; b++) {
                lap[a][b] += area * (grad[a][0] * grad[b][0] + grad[a][1] * grad[b][1]);
            }
        }
    }
    double lambda = 0.0;
    for (int a = 0; a < nodes_per; a++) {
        double sum = 0.0;
        for (int b = 0; b < nodes_per; b++) {
            double l = a <= b ? lap[a][b] : lap[b][a];
            double ma = nodal_area[a * count + e], mb = nodal_area[b * count + e];
            double s = a <= b ? rho_h * sqrt(ma * mb) : rho_h * sqrt(mb * ma);
            sum += fabs(l) / s;
        }
        /* f64::max: a NaN sum is passed over. */
        if (sum > lambda) {
            lambda = sum;
        }
    }
    if (resin->locking != 0.0) {
        double worst = 0.0;
        for (int p = 0; p < points; p++) {
            const double *g = grad + (p * nodes_per * 2) * count + e;
            double f[3][2] = {{0.0, 0.0}, {0.0, 0.0}, {0.0, 0.0}};
            for (int a = 0; a < nodes_per; a++) {
                for (int r = 0; r < 3; r++) {
                    f[r][0] += xe[a][r] * g[(2 * a) * count];
                    f[r][1] += xe[a][r] * g[(2 * a + 1) * count];
                }
            }
            double u[2][3], len[2], c;
            double t = 1.0 / 0.0;
            if (drape_locking_fibres(f, u, len, &c)) {
                t = drape_locking_tangent(resin, fabs(asin(c)));
            }
            /* f64::max: a NaN is passed over. */
            if (t > worst) {
                worst = t;
            }
        }
        kappa += 2.0 * resin->fabric_thickness * worst;
    }
    return 2.0 / sqrt(kappa * lambda);
}

#endif
