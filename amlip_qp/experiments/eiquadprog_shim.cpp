// eiquadprog-fast, TSID's QP solver, for `amlip-qp bench qp`: one workspace and one solve call
// with a C interface (amlip_qp/experiments/qp_runner_eiquadprog.py loads it with ctypes).
//
// The problem (eiquadprog-fast's form):
//   min 1/2 x' H x + g' x   s.t.   CE x + ce0 = 0,   CI x + ci0 >= 0
// with every matrix given row-major (numpy's C order) and copied into the workspace's Eigen
// matrices on each call, as a whole-body controller fills its own matrices before solving.
#include <eiquadprog/eiquadprog-fast.hpp>

#include <new>

namespace {

using eiquadprog::solvers::EiquadprogFast;
typedef Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> RowMajorMatrix;

struct Workspace {
  EiquadprogFast solver;
  Eigen::MatrixXd H, CE, CI;
  Eigen::VectorXd g, ce0, ci0, x;
  int n = -1, n_eq = -1, n_in = -1;
};

}  // namespace

extern "C" {

// A new workspace, or NULL when out of memory.
void* amlip_eiquadprog_new(void) { return new (std::nothrow) Workspace(); }

void amlip_eiquadprog_free(void* workspace) { delete static_cast<Workspace*>(workspace); }

// Solve one problem of n variables, n_eq equality rows and n_in inequality rows into x (n
// entries); *iterations receives the active-set iterations. Returns eiquadprog-fast's status:
// 0 optimal, 1 infeasible, 2 unbounded (what it returns for an infeasible problem: the dual method
// finds the dual unbounded), 3 iteration limit, 4 redundant equalities.
int amlip_eiquadprog_solve(void* workspace, int n, int n_eq, int n_in, const double* H, const double* g,
                           const double* CE, const double* ce0, const double* CI, const double* ci0, double* x,
                           int* iterations) {
  Workspace& w = *static_cast<Workspace*>(workspace);
  if (n != w.n || n_eq != w.n_eq || n_in != w.n_in) {
    w.solver.reset(n, n_eq, n_in);
    w.H.resize(n, n);
    w.CE.resize(n_eq, n);
    w.CI.resize(n_in, n);
    w.g.resize(n);
    w.ce0.resize(n_eq);
    w.ci0.resize(n_in);
    w.x.resize(n);
    w.n = n;
    w.n_eq = n_eq;
    w.n_in = n_in;
  }
  w.H = Eigen::Map<const RowMajorMatrix>(H, n, n);
  w.g = Eigen::Map<const Eigen::VectorXd>(g, n);
  w.CE = Eigen::Map<const RowMajorMatrix>(CE, n_eq, n);
  w.ce0 = Eigen::Map<const Eigen::VectorXd>(ce0, n_eq);
  w.CI = Eigen::Map<const RowMajorMatrix>(CI, n_in, n);
  w.ci0 = Eigen::Map<const Eigen::VectorXd>(ci0, n_in);
  const int status = static_cast<int>(w.solver.solve_quadprog(w.H, w.g, w.CE, w.ce0, w.CI, w.ci0, w.x));
  Eigen::Map<Eigen::VectorXd>(x, n) = w.x;
  *iterations = w.solver.getIteratios();
  return status;
}

}  // extern "C"
