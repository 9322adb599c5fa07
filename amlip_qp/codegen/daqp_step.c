/* One hot-started DAQP solve of a fixed-shape QP and its checks, in one call.
 *
 * Part of amlip_qp (amlip_qp/codegen/daqp_step.py compiles and loads it).
 *
 * amlip_daqp_step: a small QP of fixed shape (the step-timing MPC's). The
 * problem arrives as one array in DAQP's order, (H row-major, f, A row-major,
 * lower, upper), n variables and m rows, the bounds of x first in lower and upper.
 * amlip_daqp_step copies it into the workspace's arrays, clamps the bounds to
 * +-big (NaN stays NaN, as numpy's minimum and maximum leave it), calls DAQP's
 * daqp_update_ldp and daqp_solve (their addresses are handed over from the daqp
 * Python package's library), and, when DAQP reports the problem solved, computes
 * the largest violation of the bounds of x and of the checked rows at the
 * solution (NaN when any is NaN). It is the sequence of
 * amlip_qp.qp.small_qp.SmallQPSolver's Python path, with the same DAQP calls on
 * the same data: the same solution, bit for bit.
 *
 * With a producer (a CasADi-generated function, e.g. the step-timing MPC's
 * alip_mpc_qp), the call's input is the producer's input instead: the producer
 * writes the problem straight into the workspace's arrays.
 */
#include <math.h>
#include <string.h>

typedef int (*amlip_daqp_update_fn)(int mask, void *work, void *problem);
typedef void (*amlip_daqp_solve_fn)(void *result, void *work);
typedef int (*amlip_casadi_fn)(const double **arg, double **res, long long *iw, double *w, int mem);

typedef struct {
    amlip_daqp_update_fn update;
    amlip_daqp_solve_fn solve;
    void *work;         /* DAQP's workspace, set up on `data` */
    void *problem;      /* DAQP's problem, pointing into `data` */
    void *result;       /* DAQP's result, its x pointing at `x` */
    double *data;       /* n*n + n + m*n + 2*(n + m): H, f, A, lower, upper */
    const double *x;    /* DAQP's solution, n */
    const double *hard; /* n + m: 1 checked, 0 not (soft rows) */
    int n;
    int m;
    int update_mask;
    int exitflag_offset; /* bytes from `result` to DAQP's exit flag (an int) */
    double big;
    double violation;   /* out: the largest violation, when solved */
    amlip_casadi_fn producer; /* NULL: the input is the problem itself */
    const double **producer_arg;
    double **producer_res;
    long long *producer_iw;
    double *producer_w;
} amlip_daqp_step_t;

int amlip_daqp_step(amlip_daqp_step_t *c, const double *src)
{
    const int n = c->n, m = c->m, nb = n + m;
    const int n_matrices = n * n + n + m * n;
    double *d = c->data;
    double *lower = d + n_matrices, *upper = lower + nb;
    const double *A = d + n * n + n;
    const double big = c->big;
    int i, k, flag;
    double worst = -INFINITY;

    if (c->producer) {
        c->producer_arg[0] = src;
        c->producer_res[0] = d;
        flag = c->producer(c->producer_arg, c->producer_res, c->producer_iw, c->producer_w, 0);
        if (flag != 0) return -1000 - flag; /* the producer failed: not a DAQP exit flag */
    } else {
        memcpy(d, src, sizeof(double) * (size_t)(n_matrices + 2 * nb));
    }
    for (i = 0; i < nb; ++i) {
        double lo = lower[i], up = upper[i];
        if (!(lo != lo || lo > -big)) lower[i] = -big;
        if (!(up != up || up < big)) upper[i] = big;
    }
    c->update(c->update_mask, c->work, c->problem);
    c->solve(c->result, c->work);
    memcpy(&flag, (const char *)c->result + c->exitflag_offset, sizeof(int));
    if (flag != 1 && flag != 2) return flag;
    for (i = 0; i < nb; ++i) {
        double z, below, above, gap;
        if (i < n) {
            z = c->x[i];
        } else {
            const double *row = A + (size_t)(i - n) * n;
            z = 0.0;
            for (k = 0; k < n; ++k) z += row[k] * c->x[k];
        }
        below = lower[i] - z;
        above = z - upper[i];
        gap = (below != below || above != above) ? NAN : (below > above ? below : above);
        gap *= c->hard[i];
        if (gap != gap) {
            worst = NAN;
            break;
        }
        if (gap > worst) worst = gap;
    }
    c->violation = worst;
    return flag;
}

/* amlip_daqp_rows: the QP tracker's problem (amlip_qp.qp.daqp_solver.DAQPSolver), which keeps
 * its data where its builder wrote it: H, f and the rows [C; A] in place, the bounds of x and of
 * the inequality rows stacked (lower, upper: n + n_in), the equalities' right side b (n_eq).
 * DAQP's bounds bl, bu (n + n_in + n_eq) are those clamped to +-big, then b on both sides (the
 * equalities); then DAQP's update and solve, and, when solved, the largest of bl - z and z - bu
 * over z = (x, C x, A x) (NaN when any is NaN): DAQPSolver's Python sequence, the same solution
 * bit for bit. With check_problem set, first QPProblem.validate's test of an allocated problem:
 * every entry of data (H, g, C, A, b: n_data) finite and lower <= upper (a NaN bound fails); if
 * either fails, AMLIP_DAQP_INVALID (daqp_step.py's INVALID_PROBLEM) is returned and DAQP is not
 * called. */
#define AMLIP_DAQP_INVALID (-200)

typedef struct {
    amlip_daqp_update_fn update;
    amlip_daqp_solve_fn solve;
    void *work;
    void *problem;
    void *result;
    const double *lower;
    const double *upper;
    const double *b;
    double *bl;
    double *bu;
    const double *rows; /* (n_in + n_eq) x n, row-major */
    const double *x;
    const double *data; /* H, g, C, A, b of the allocated problem, for the check */
    int n;
    int n_in;
    int n_eq;
    int update_mask;
    int exitflag_offset;
    int n_data;
    int check_problem;
    double big;
    double gap; /* out: the largest violation, when solved */
} amlip_daqp_rows_t;

/* Whether the n entries of a are all finite (no NaN, no inf): their exponent bits never all set. */
static int amlip_all_finite(const double *a, int n)
{
    const unsigned long long exponent = 0x7ff0000000000000ULL;
    unsigned long long bits, bad = 0;
    int i;
    for (i = 0; i < n; ++i) {
        memcpy(&bits, a + i, sizeof bits);
        bad |= (unsigned long long)((bits & exponent) == exponent);
    }
    return !bad;
}

int amlip_daqp_rows(amlip_daqp_rows_t *c)
{
    const int n = c->n, nb = n + c->n_in, m = nb + c->n_eq;
    const double big = c->big;
    int i, k, flag;
    double worst = -INFINITY;

    if (c->check_problem) {
        int crossed = 0;
        for (i = 0; i < nb; ++i) crossed |= !(c->lower[i] <= c->upper[i]);
        if (crossed || !amlip_all_finite(c->data, c->n_data)) return AMLIP_DAQP_INVALID;
    }
    for (i = 0; i < nb; ++i) {
        double lo = c->lower[i], up = c->upper[i];
        c->bl[i] = (lo != lo || lo > -big) ? lo : -big;
        c->bu[i] = (up != up || up < big) ? up : big;
    }
    for (i = nb; i < m; ++i) c->bl[i] = c->bu[i] = c->b[i - nb];
    c->update(c->update_mask, c->work, c->problem);
    c->solve(c->result, c->work);
    memcpy(&flag, (const char *)c->result + c->exitflag_offset, sizeof(int));
    if (flag != 1 && flag != 2) return flag;
    for (i = 0; i < m; ++i) {
        double z, below, above;
        if (i < n) {
            z = c->x[i];
        } else {
            const double *row = c->rows + (size_t)(i - n) * n;
            z = 0.0;
            for (k = 0; k < n; ++k) z += row[k] * c->x[k];
        }
        below = c->bl[i] - z;
        above = z - c->bu[i];
        if (below != below || above != above) {
            worst = NAN;
            break;
        }
        if (below > worst) worst = below;
        if (above > worst) worst = above;
    }
    c->gap = worst;
    return flag;
}
