/* Internal forces of the walled pendulum and of the FPU-beta chain for the Siconos peer
   (peers_siconos.py), with their Jacobians, as a Siconos plugin (built as WallsPlugin.so).
   Siconos's Lagrangian systems read M q'' + F_int(t, q, v) = F_ext + p, so F_int = grad V.
   Signature of an F_int plugin: (t, size of q, q, v, out, size of z, z); Jacobians column-major.
   Parameters as in vci_results_common.f90. */
#include <string.h>
#include <math.h>
static const double G = 9.8, L = 1.0, BETA = 1.0;

void pendulum_fint(double t, unsigned int n, double* q, double* v, double* f, unsigned int nz, double* z)
{ f[0] = G * L * sin(q[0]); }   /* m l^2 = l^2 = 1: theta'' = -(g/l) sin theta with m = 1, l = 1 */
void pendulum_jacq(double t, unsigned int n, double* q, double* v, double* jac, unsigned int nz, double* z)
{ jac[0] = G * L * cos(q[0]); }
void zero_jac(double t, unsigned int n, double* q, double* v, double* jac, unsigned int nz, double* z)
{ memset(jac, 0, sizeof(double) * n * n); }

/* stretches r_j = x_{j+1} - x_j, j = 0..n, with x_0 = x_{n+1} = 0 */
static double stretch(unsigned int n, const double* x, unsigned int j)
{ double a = (j == 0) ? 0.0 : x[j - 1], b = (j == n) ? 0.0 : x[j]; return b - a; }

void fpu_fint(double t, unsigned int n, double* q, double* v, double* f, unsigned int nz, double* z)
{ /* dV/dx_i = V'(r_{i-1}) - V'(r_i), V'(r) = r + beta r^3 (i = 1..n; r index i-1 and i) */
  for (unsigned int i = 0; i < n; ++i) {
    double a = stretch(n, q, i), b = stretch(n, q, i + 1);
    f[i] = (a + BETA * a * a * a) - (b + BETA * b * b * b);
  } }
void fpu_jacq(double t, unsigned int n, double* q, double* v, double* jac, unsigned int nz, double* z)
{ memset(jac, 0, sizeof(double) * n * n);
  for (unsigned int i = 0; i < n; ++i) {
    double a = stretch(n, q, i), b = stretch(n, q, i + 1);
    double ka = 1.0 + 3.0 * BETA * a * a, kb = 1.0 + 3.0 * BETA * b * b;
    jac[i + n * i] = ka + kb;
    if (i + 1 < n) { jac[i + n * (i + 1)] = -kb; jac[(i + 1) + n * i] = -kb; }
  } }
