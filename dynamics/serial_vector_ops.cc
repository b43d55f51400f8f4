#include "dynamics/serial_vector_ops.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Core>

namespace coaxid {
namespace {

inline double* Data(N_Vector v) { return NV_DATA_S(v); }
inline sunindextype Length(N_Vector v) { return NV_LENGTH_S(v); }

// Each loop reads element k of every input before writing element k of the
// output, so an output that aliases an input is handled as SUNDIALS does.
void LinearSum(realtype a, N_Vector x, realtype b, N_Vector y, N_Vector z) {
  const double *xd = Data(x), *yd = Data(y);
  double* zd = Data(z);
  for (sunindextype k = 0, n = Length(x); k < n; ++k) zd[k] = a * xd[k] + b * yd[k];
}
void Const(realtype c, N_Vector z) {
  double* zd = Data(z);
  for (sunindextype k = 0, n = Length(z); k < n; ++k) zd[k] = c;
}
void Prod(N_Vector x, N_Vector y, N_Vector z) {
  const double *xd = Data(x), *yd = Data(y);
  double* zd = Data(z);
  for (sunindextype k = 0, n = Length(x); k < n; ++k) zd[k] = xd[k] * yd[k];
}
void Div(N_Vector x, N_Vector y, N_Vector z) {
  const double *xd = Data(x), *yd = Data(y);
  double* zd = Data(z);
  for (sunindextype k = 0, n = Length(x); k < n; ++k) zd[k] = xd[k] / yd[k];
}
void Scale(realtype c, N_Vector x, N_Vector z) {
  const double* xd = Data(x);
  double* zd = Data(z);
  for (sunindextype k = 0, n = Length(x); k < n; ++k) zd[k] = c * xd[k];
}
void Abs(N_Vector x, N_Vector z) {
  const double* xd = Data(x);
  double* zd = Data(z);
  for (sunindextype k = 0, n = Length(x); k < n; ++k) zd[k] = std::fabs(xd[k]);
}
void Inv(N_Vector x, N_Vector z) {
  const double* xd = Data(x);
  double* zd = Data(z);
  for (sunindextype k = 0, n = Length(x); k < n; ++k) zd[k] = 1.0 / xd[k];
}
void AddConst(N_Vector x, realtype b, N_Vector z) {
  const double* xd = Data(x);
  double* zd = Data(z);
  for (sunindextype k = 0, n = Length(x); k < n; ++k) zd[k] = xd[k] + b;
}
// Reductions through Eigen, which vectorises them (a plain loop with one
// running sum is a serial dependency the compiler may not reorder; WrmsNorm
// on the 300-long state of a variational system was 10 % of an output-error
// fit before).
Eigen::Map<const Eigen::ArrayXd> Array(N_Vector v) { return {Data(v), Length(v)}; }
realtype MaxNorm(N_Vector x) { return Length(x) > 0 ? Array(x).abs().maxCoeff() : 0.0; }
realtype WSqrSumLocal(N_Vector x, N_Vector w) { return (Array(x) * Array(w)).square().sum(); }
realtype WrmsNorm(N_Vector x, N_Vector w) {
  return std::sqrt(WSqrSumLocal(x, w) / static_cast<double>(Length(x)));
}
realtype WrmsNormMask(N_Vector x, N_Vector w, N_Vector id) {
  const double *xd = Data(x), *wd = Data(w), *idd = Data(id);
  double s = 0;
  for (sunindextype k = 0, n = Length(x); k < n; ++k) {
    if (idd[k] > 0) {
      const double p = xd[k] * wd[k];
      s += p * p;
    }
  }
  return std::sqrt(s / static_cast<double>(Length(x)));
}
int LinearCombination(int nv, realtype* c, N_Vector* X, N_Vector z) {
  double* zd = Data(z);
  const sunindextype n = Length(z);
  if (nv == 1) {
    Scale(c[0], X[0], z);
    return 0;
  }
  // One vectorised pass per term, same order of summation. z may be X[0]
  // (read before it is written); any other aliasing takes the element loop.
  if (std::find(X + 1, X + nv, z) == X + nv) {
    Eigen::Map<Eigen::ArrayXd> out(zd, n);
    out = c[0] * Array(X[0]);
    for (int i = 1; i < nv; ++i) out += c[i] * Array(X[i]);
    return 0;
  }
  for (sunindextype k = 0; k < n; ++k) {
    double s = 0;
    for (int i = 0; i < nv; ++i) s += c[i] * Data(X[i])[k];
    zd[k] = s;
  }
  return 0;
}
int ScaleAddMulti(int nv, realtype* a, N_Vector x, N_Vector* Y, N_Vector* Z) {
  const double* xd = Data(x);
  const sunindextype n = Length(x);
  for (int i = 0; i < nv; ++i) {
    const double* yd = Data(Y[i]);
    double* zd = Data(Z[i]);
    for (sunindextype k = 0; k < n; ++k) zd[k] = a[i] * xd[k] + yd[k];
  }
  return 0;
}
int LinearSumVectorArray(int nv, realtype a, N_Vector* X, realtype b, N_Vector* Y,
                         N_Vector* Z) {
  for (int i = 0; i < nv; ++i) LinearSum(a, X[i], b, Y[i], Z[i]);
  return 0;
}
int ScaleVectorArray(int nv, realtype* c, N_Vector* X, N_Vector* Z) {
  for (int i = 0; i < nv; ++i) Scale(c[i], X[i], Z[i]);
  return 0;
}
int ConstVectorArray(int nv, realtype c, N_Vector* Z) {
  for (int i = 0; i < nv; ++i) Const(c, Z[i]);
  return 0;
}
int WrmsNormVectorArray(int nv, N_Vector* X, N_Vector* W, realtype* norms) {
  for (int i = 0; i < nv; ++i) norms[i] = WrmsNorm(X[i], W[i]);
  return 0;
}
int ScaleAddMultiVectorArray(int nv, int ns, realtype* a, N_Vector* X, N_Vector** Y,
                             N_Vector** Z) {
  // Z[j][i] = a[j] X[i] + Y[j][i]
  for (int i = 0; i < nv; ++i) {
    const double* xd = Data(X[i]);
    const sunindextype n = Length(X[i]);
    for (int j = 0; j < ns; ++j) {
      const double* yd = Data(Y[j][i]);
      double* zd = Data(Z[j][i]);
      for (sunindextype k = 0; k < n; ++k) zd[k] = a[j] * xd[k] + yd[k];
    }
  }
  return 0;
}
int LinearCombinationVectorArray(int nv, int ns, realtype* c, N_Vector** X, N_Vector* Z) {
  // Z[i] = sum_j c[j] X[j][i]
  for (int i = 0; i < nv; ++i) {
    double* zd = Data(Z[i]);
    const sunindextype n = Length(Z[i]);
    for (sunindextype k = 0; k < n; ++k) {
      double s = 0;
      for (int j = 0; j < ns; ++j) s += c[j] * Data(X[j][i])[k];
      zd[k] = s;
    }
  }
  return 0;
}

}  // namespace

void UseOptimizedSerialOps(N_Vector v) {
  N_Vector_Ops ops = v->ops;
  ops->nvlinearsum = LinearSum;
  ops->nvconst = Const;
  ops->nvprod = Prod;
  ops->nvdiv = Div;
  ops->nvscale = Scale;
  ops->nvabs = Abs;
  ops->nvinv = Inv;
  ops->nvaddconst = AddConst;
  ops->nvmaxnorm = MaxNorm;
  ops->nvmaxnormlocal = MaxNorm;
  ops->nvwrmsnorm = WrmsNorm;
  ops->nvwrmsnormmask = WrmsNormMask;
  ops->nvwsqrsumlocal = WSqrSumLocal;
  // Fused and vector-array kernels only where SUNDIALS enabled them (fused ops on).
  if (ops->nvlinearcombination) ops->nvlinearcombination = LinearCombination;
  if (ops->nvscaleaddmulti) ops->nvscaleaddmulti = ScaleAddMulti;
  if (ops->nvlinearsumvectorarray) ops->nvlinearsumvectorarray = LinearSumVectorArray;
  if (ops->nvscalevectorarray) ops->nvscalevectorarray = ScaleVectorArray;
  if (ops->nvconstvectorarray) ops->nvconstvectorarray = ConstVectorArray;
  if (ops->nvwrmsnormvectorarray) ops->nvwrmsnormvectorarray = WrmsNormVectorArray;
  if (ops->nvscaleaddmultivectorarray) {
    ops->nvscaleaddmultivectorarray = ScaleAddMultiVectorArray;
  }
  if (ops->nvlinearcombinationvectorarray) {
    ops->nvlinearcombinationvectorarray = LinearCombinationVectorArray;
  }
}

}  // namespace coaxid
