/* drape's explicit step on the GPU: one thread per truss, quad, spring or
 * node over the functions of kernels/step.h (which precedes this file in
 * the source NVRTC compiles). A failing element records the lowest index
 * in fault[kind] (0 truss, 1 quad, 2 contact, 3 bending: an integer
 * minimum, the same whatever the order). */

#define DRAPE_INDEX ((long)blockIdx.x * (long)blockDim.x + (long)threadIdx.x)

extern "C" __global__ void truss_forces(long count, double modulus, double crimp_strain,
                                        double compression_factor, double buckling_stress,
                                        const unsigned *nodes, const double *length,
                                        const double *section, int has_dashpot,
                                        const double *dashpot, const double *x,
                                        const double *v, long n, double *slots,
                                        long slot_count, long first, int *fault)
{
    long e = DRAPE_INDEX;
    if (e >= count) {
        return;
    }
    DrapeFibreLaw law = {modulus, crimp_strain, compression_factor, buckling_stress};
    if (drape_truss_force(e, law, nodes, length, section, has_dashpot ? dashpot : 0, x, v, n,
                          slots, slot_count, first)) {
        atomicMin(fault, (int)e);
    }
}

extern "C" __global__ void triangle_forces(long count, const DrapeResinStep *resin,
                                       const unsigned *nodes, const double *grad,
                                       const double *area, double *history, long stride,
                                       int commit, const double *x, long n, double *slots,
                                       long slot_count, long first, int *fault)
{
    long e = DRAPE_INDEX;
    if (e >= count) {
        return;
    }
    if (drape_triangle_force(e, count, resin, nodes, grad, area, history, stride, commit, x, n,
                         slots, slot_count, first)) {
        atomicMin(fault + 1, (int)e);
    }
}

extern "C" __global__ void bending_forces(long count, const unsigned *nodes,
                                          const double *stiffness, const double *x, long n,
                                          double *slots, long slot_count, long first,
                                          int *fault)
{
    long e = DRAPE_INDEX;
    if (e >= count) {
        return;
    }
    if (drape_bending_force(e, nodes, stiffness, x, n, slots, slot_count, first)) {
        atomicMin(fault + 3, (int)e);
    }
}

extern "C" __global__ void spring_forces(long count, const unsigned *nodes,
                                         const double *anchor, const double *rest,
                                         const long *table_start, const long *table_len,
                                         const double *extension, const double *table_force,
                                         const double *x, long n, double *slots,
                                         long slot_count, long first)
{
    long e = DRAPE_INDEX;
    if (e >= count) {
        return;
    }
    drape_spring_force(e, nodes, anchor, rest, table_start, table_len, extension, table_force,
                       count, x, n, slots, slot_count, first);
}

extern "C" __global__ void gather(long n, const long *ptr, const unsigned *node_slots,
                                  const double *slots, long slot_count, double *f_int)
{
    long i = DRAPE_INDEX;
    if (i >= n) {
        return;
    }
    drape_gather(i, ptr, node_slots, slots, slot_count, f_int, n);
}

/* The stable steps: each element's into the smallest of its batch, an
 * integer minimum on the bits of a positive double (NaN, above +inf, is
 * passed over as f64::min does). */
#define DRAPE_MIN_STEP(out, dt) atomicMin((unsigned long long *)(out), \
                                          (unsigned long long)__double_as_longlong(dt))

extern "C" __global__ void truss_steps(long count, double wave_modulus, const unsigned *nodes,
                                       const double *section, const double *share,
                                       const double *x, long n, double *out)
{
    long e = DRAPE_INDEX;
    if (e < count) {
        DRAPE_MIN_STEP(out, drape_truss_step(e, wave_modulus, nodes, section, share, x, n));
    }
}

extern "C" __global__ void bending_steps(long count, const unsigned *nodes,
                                         const double *stiffness, const double *share,
                                         const double *x, long n, double *out)
{
    long e = DRAPE_INDEX;
    if (e < count) {
        DRAPE_MIN_STEP(out, drape_bending_step(e, nodes, stiffness, share, x, n));
    }
}

extern "C" __global__ void spring_steps(long count, const unsigned *nodes, const double *anchor,
                                        const double *rest, const long *table_start,
                                        const long *table_len, const double *extension,
                                        const double *table_force, double max_stiffness,
                                        const double *mass, const double *x, long n,
                                        double *out)
{
    long e = DRAPE_INDEX;
    if (e < count) {
        DRAPE_MIN_STEP(out, drape_spring_step(e, nodes, anchor, rest, table_start, table_len,
                                              extension, table_force, max_stiffness, count,
                                              mass, x, n));
    }
}

extern "C" __global__ void membrane_steps(long count, int nodes_per, int points,
                                          const unsigned *nodes, const double *nodal_area,
                                          const DrapeResinStep *resin, const double *grad,
                                          const double *scale, double kappa, double rho_h,
                                          const double *x, long n, double *out)
{
    long e = DRAPE_INDEX;
    if (e < count) {
        double dt = nodes_per == 4 ? drape_membrane_step(e, count, 4, 4, nodes, nodal_area, resin,
                                                         grad, kappa, rho_h, x, n)
                                   : drape_membrane_step(e, count, 3, 1, nodes, nodal_area, resin,
                                                         grad, kappa, rho_h, x, n);
        DRAPE_MIN_STEP(out, dt * scale[e]);
    }
}

/* Resin-only quads, four threads a quad (one per integration point, the
 * four lanes of a group in one warp): each lane its point's kinematics,
 * stress update and shares of the nodal forces (kernels/step.h's
 * functions); the quad refused as a whole if one point is degenerate;
 * the shares summed from zero in point order on the lane of point 0, as
 * drape_membrane_force sums them. Needs whole warps (threads per block a
 * multiple of 32). */
extern "C" __global__ void quad_point_forces(long count, const DrapeResinStep *resin,
                                             const unsigned *nodes, const double *grad,
                                             const double *area, double *history, long stride,
                                             int commit, const double *x, long n, double *slots,
                                             long slot_count, long first, int *fault)
{
    long t = DRAPE_INDEX;
    long e = t >> 2;
    int p = (int)(t & 3);
    if (e >= count) {
        return;
    }
    unsigned lane = threadIdx.x & 31u;
    unsigned base = lane & ~3u;
    unsigned group = 0xFu << base;
    double xe[4][3];
    drape_membrane_nodes(e, 4, nodes, x, xe);
    double f[3][2], c[5];
    int ok = drape_membrane_kinematics(e, 4, p, count, grad, resin, xe, f, c);
    if (!__all_sync(group, ok)) {
        if (p == 0) {
            atomicMin(fault + 1, (int)e);
        }
        return;
    }
    double share[4][3];
    drape_membrane_point(e, 4, p, count, resin, grad, area, history, stride, commit, f, c, share);
    for (int a = 0; a < 4; a++) {
        for (int r = 0; r < 3; r++) {
            double s1 = __shfl_sync(group, share[a][r], base + 1);
            double s2 = __shfl_sync(group, share[a][r], base + 2);
            double s3 = __shfl_sync(group, share[a][r], base + 3);
            double sum = 0.0;
            sum += share[a][r];
            sum += s1;
            sum += s2;
            sum += s3;
            share[a][r] = sum;
        }
    }
    if (p == 0) {
        for (int a = 0; a < 4; a++) {
            long s = first + 4 * e + a;
            slots[3 * s] = share[a][0];
            slots[3 * s + 1] = share[a][1];
            slots[3 * s + 2] = share[a][2];
        }
    }
}

/* Node i's gather of the last step's element forces, then its next step
 * (update, contact, works): one kernel where two would each wait for the
 * whole grid, as node i's step reads node i's force alone. */
extern "C" __global__ void gather_node_step(long n, const long *ptr, const unsigned *node_slots,
                                            const double *slots, long slot_count,
                                            const double *params, const double *x,
                                            const double *v, const double *weight,
                                            const long *load_ptr, const unsigned *load_of,
                                            int has_loads, const double *loads,
                                            const long *p_ptr, const unsigned *p_slot,
                                            const unsigned *p_nodes,
                                            const unsigned char *p_count,
                                            const unsigned *p_load, int has_pressure,
                                            const double *scales,
                                            double *f_int, const double *mass,
                                            const unsigned char *fixed, const double *x0,
                                            const int *moving, const double *held,
                                            int has_tool, const double *tool, double *x_new,
                                            double *v_new, double *contact_force,
                                            unsigned char *status, double *sums, int *fault)
{
    long i = DRAPE_INDEX;
    if (i >= n) {
        return;
    }
    drape_gather(i, ptr, node_slots, slots, slot_count, f_int, n);
    int kind = drape_node_step(i, n, params, x, v, weight, load_ptr, load_of,
                               has_loads ? loads : 0, p_ptr, p_slot, p_nodes, p_count, p_load,
                               has_pressure ? scales : 0, f_int, mass, fixed, x0, moving, held,
                               has_tool ? tool : 0, x_new, v_new, contact_force, status, sums);
    if (kind) {
        atomicMin(fault + 2, (int)(4 * i + kind));
    }
}
