/* The CPU build of drape's GPU kernels (kernels/step.h): each kernel's
 * per-thread function called in a loop, so that the arithmetic the GPU runs
 * is tested against the CPU driver on a machine without a GPU. Each loop
 * returns the lowest failing element, or -1. */

#include "step.h"

/* Bytes of a DrapeResinStep: what layout.rs's step() fills. */
long drape_host_resin_step_size(void)
{
    return (long)sizeof(DrapeResinStep);
}

long drape_host_truss_forces(long count, DrapeFibreLaw law, const unsigned *nodes,
                             const double *length, const double *section,
                             const double *dashpot, const double *x, const double *v,
                             long n, double *slots, long slot_count, long first)
{
    for (long e = 0; e < count; e++) {
        if (drape_truss_force(e, law, nodes, length, section, dashpot, x, v, n, slots,
                              slot_count, first)) {
            return e;
        }
    }
    return -1;
}

long drape_host_quad_forces(long count, const DrapeResinStep *resin, const unsigned *nodes,
                            const double *grad, const double *area, double *history,
                            long stride, int commit, const double *x, long n, double *slots,
                            long slot_count, long first)
{
    for (long e = 0; e < count; e++) {
        if (drape_quad_force(e, count, resin, nodes, grad, area, history, stride, commit, x, n,
                             slots, slot_count, first)) {
            return e;
        }
    }
    return -1;
}

long drape_host_triangle_forces(long count, const DrapeResinStep *resin, const unsigned *nodes,
                            const double *grad, const double *area, double *history,
                            long stride, int commit, const double *x, long n, double *slots,
                            long slot_count, long first)
{
    for (long e = 0; e < count; e++) {
        if (drape_triangle_force(e, count, resin, nodes, grad, area, history, stride, commit, x, n,
                             slots, slot_count, first)) {
            return e;
        }
    }
    return -1;
}

long drape_host_bending_forces(long count, const unsigned *nodes, const double *stiffness,
                               const double *x, long n, double *slots, long slot_count,
                               long first)
{
    for (long e = 0; e < count; e++) {
        if (drape_bending_force(e, nodes, stiffness, x, n, slots, slot_count, first)) {
            return e;
        }
    }
    return -1;
}

void drape_host_spring_forces(long count, const unsigned *nodes, const double *anchor,
                              const double *rest, const long *table_start,
                              const long *table_len, const double *extension,
                              const double *table_force, const double *x, long n,
                              double *slots, long slot_count, long first)
{
    for (long e = 0; e < count; e++) {
        drape_spring_force(e, nodes, anchor, rest, table_start, table_len, extension,
                           table_force, count, x, n, slots, slot_count, first);
    }
}

void drape_host_gather(long n, const long *ptr, const unsigned *node_slots, const double *slots,
                       long slot_count, double *f_int)
{
    for (long i = 0; i < n; i++) {
        drape_gather(i, ptr, node_slots, slots, slot_count, f_int, n);
    }
}

long drape_host_node_step(long n, const double *params, const double *x, const double *v,
                          const double *weight, const long *load_ptr, const unsigned *load_of,
                          const double *loads, const long *p_ptr, const unsigned *p_slot,
                          const unsigned *p_nodes, const unsigned char *p_count,
                          const unsigned *p_load, const double *scales, const double *f_int,
                          const double *mass,
                          const unsigned char *fixed, const double *x0, const int *moving,
                          const double *held, const double *tool, double *x_new,
                          double *v_new, double *contact_force, unsigned char *status,
                          double *sums)
{
    long first = -1;
    for (long i = 0; i < n; i++) {
        int fault = drape_node_step(i, n, params, x, v, weight, load_ptr, load_of, loads, p_ptr,
                                    p_slot, p_nodes, p_count, p_load, scales, f_int, mass, fixed,
                                    x0, moving, held, tool, x_new, v_new, contact_force, status,
                                    sums);
        if (fault && first < 0) {
            first = 4 * i + fault;
        }
    }
    return first;
}

/* The stable steps: the smallest of each batch (positive doubles; NaN
 * passed over, as f64::min does), +inf for none. */
double drape_host_truss_steps(long count, double wave_modulus, const unsigned *nodes,
                              const double *section, const double *share, const double *x,
                              long n)
{
    double best = 1.0 / 0.0;
    for (long e = 0; e < count; e++) {
        double dt = drape_truss_step(e, wave_modulus, nodes, section, share, x, n);
        if (dt < best) {
            best = dt;
        }
    }
    return best;
}

double drape_host_bending_steps(long count, const unsigned *nodes, const double *stiffness,
                                const double *share, const double *x, long n)
{
    double best = 1.0 / 0.0;
    for (long e = 0; e < count; e++) {
        double dt = drape_bending_step(e, nodes, stiffness, share, x, n);
        if (dt < best) {
            best = dt;
        }
    }
    return best;
}

double drape_host_spring_steps(long count, const unsigned *nodes, const double *anchor,
                               const double *rest, const long *table_start,
                               const long *table_len, const double *extension,
                               const double *table_force, double max_stiffness,
                               const double *mass, const double *x, long n)
{
    double best = 1.0 / 0.0;
    for (long e = 0; e < count; e++) {
        double dt = drape_spring_step(e, nodes, anchor, rest, table_start, table_len, extension,
                                      table_force, max_stiffness, count, mass, x, n);
        if (dt < best) {
            best = dt;
        }
    }
    return best;
}

double drape_host_membrane_steps(long count, int nodes_per, int points, const unsigned *nodes,
                                 const double *nodal_area, const DrapeResinStep *resin,
                                 const double *grad, const double *scale, double kappa,
                                 double rho_h, const double *x, long n)
{
    double best = 1.0 / 0.0;
    for (long e = 0; e < count; e++) {
        double dt = drape_membrane_step(e, count, nodes_per, points, nodes, nodal_area, resin,
                                        grad, kappa, rho_h, x, n) *
                    scale[e];
        if (dt < best) {
            best = dt;
        }
    }
    return best;
}
