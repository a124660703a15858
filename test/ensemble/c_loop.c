/* The C ensemble loop of docs/ENSEMBLES.md ("From C"), included from the page itself: every member
 * created, integrated and destroyed on an OpenMP thread, handles of many members created and
 * destroyed on several threads at once (vci.h, "Threads"). Members are the
 * paper's ellipse with its start moved by 1e-12 ... 1e-2; prints every member's status and final
 * state in hexadecimal, so that runs on 1 and 2 threads can be compared bit for bit.
 * Usage: ens_c_loop [n_members] */
#include <stdio.h>
#include <stdlib.h>
#include <math.h>
#include "vci.h"
#include "scenes.h"

int main(int argc, char **argv) {
  int n_members = argc > 1 ? atoi(argv[1]) : 600, n = 3, ngaps = 1;   /* several blocks of 256 */
  long nsteps = 300;
  double h = 1e-2;
  ellipse_params par = ellipse_default;
  vci_callbacks cb = ellipse_callbacks();
  ellipse_params *user = malloc(sizeof *user * n_members);
  double *t0 = malloc(sizeof *t0 * n_members), *q0 = malloc(sizeof *q0 * 3 * n_members);
  double *q1 = malloc(sizeof *q1 * 3 * n_members), *t = malloc(sizeof *t * n_members);
  double *q = malloc(sizeof *q * 3 * n_members), *p = malloc(sizeof *p * 3 * n_members);
  int *status = malloc(sizeof *status * n_members);
  char (*msg)[256] = malloc(sizeof *msg * n_members);
  for (int i = 0; i < n_members; i++) {
    double size = i == 0 ? 0.0 : 1e-12 * pow(1e10, (double)(i - 1) / (n_members > 2 ? n_members - 2 : 1));
    user[i] = par;
    ellipse_initial_pair(h, &t0[i], &q0[3 * i], &q1[3 * i]);
    q0[3 * i] += size; q1[3 * i] += size;      /* turn the ellipse by `size` */
    t[i] = NAN; q[3 * i] = q[3 * i + 1] = q[3 * i + 2] = NAN; p[3 * i] = p[3 * i + 1] = p[3 * i + 2] = NAN;
    msg[i][0] = '\0';
  }
  q0[3 * 3 + 2] = q1[3 * 3 + 2] = 0.1;         /* member 3 starts below the floor: it must fail alone */

  {
  /* the loop of docs/ENSEMBLES.md, "From C", extracted from the page at configure time */
#include "ensembles_c_loop.inc"
  }

  int failed = 0;
  for (int i = 0; i < n_members; i++) {
    printf("%3d %d %a %a %a %a %a %a %a\n", i, status[i], t[i], q[3 * i], q[3 * i + 1], q[3 * i + 2],
           p[3 * i], p[3 * i + 1], p[3 * i + 2]);
    if (status[i]) { failed++; fprintf(stderr, "member %d: %s\n", i, msg[i]); }
  }
  /* exactly member 3 fails, as inadmissible; the others end at t = t0 + (nsteps + 1) h */
  int bad = failed != 1 || status[3] != VCI_ERR_INADMISSIBLE;
  for (int i = 0; i < n_members; i++)
    if (i != 3 && fabs(t[i] - (t0[i] + (nsteps + 1) * h)) > 1e-9) bad = 1;
  free(user); free(t0); free(q0); free(q1); free(t); free(q); free(p); free(status); free(msg);
  return bad;
}
