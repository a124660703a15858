/* The ellipse floor relation for the Siconos peer (peers_siconos.py): gap h(q) = y - phi(theta) and
   its 1x3 Jacobian, as a Siconos plugin (Python-subclassed relations crash Siconos 4.4 in
   computeOneStep, see docs/RESULTS.md). Built by CMakeLists.txt as EllipsePlugin.so. */
#include <math.h>
static const double A = 1.0, B = 0.5;
static double phi(double th) { return sqrt(A*A*sin(th)*sin(th) + B*B*cos(th)*cos(th)); }
void h(unsigned int sizeQ, double* q, unsigned int sizeY, double* y, unsigned int sizeZ, double* z)
{ y[0] = q[2] - phi(q[0]); }
void G0(unsigned int sizeQ, double* q, unsigned int sizeY, double* jac, unsigned int sizeZ, double* z)
{ /* 1 x 3, column-major */
  jac[0] = -(A*A - B*B)*sin(q[0])*cos(q[0])/phi(q[0]); jac[1] = 0.0; jac[2] = 1.0; }
