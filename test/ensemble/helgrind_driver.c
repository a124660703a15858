/* Thread-safety check of ensemble members (run under valgrind --tool=helgrind): THREADS POSIX
 * threads run members with vci_ensemble_run_member, as the OpenMP loop does, thread i members
 * i+1, i+1+THREADS, ... with no synchronisation between threads but their creation and joining,
 * so that any memory two members share is seen as a race whatever the timing; then the results
 * must equal a one-thread run bitwise.
 * Usage: ens_helgrind_driver THREADS [racy]   ("racy": the members' models share a counter) */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int ens_hooks_setup(int racy);
void ens_hooks_run(int member);
int ens_hooks_check(void);

static int n_members = 0, n_threads = 1;

static void *worker(void *arg) {
  int first = *(const int *)arg;
  for (int m = first; m <= n_members; m += n_threads) ens_hooks_run(m);
  return NULL;
}

int main(int argc, char **argv) {
  int nt = argc > 1 ? atoi(argv[1]) : 2;
  int racy = argc > 2 && strcmp(argv[2], "racy") == 0;
  pthread_t th[16];
  int first[16];
  if (nt < 1 || nt > 16) return 2;
  n_threads = nt;
  n_members = ens_hooks_setup(racy);
  if (n_members < 1) return 2;
  for (int i = 0; i < nt; i++) {
    first[i] = i + 1;
    pthread_create(&th[i], NULL, worker, &first[i]);
  }
  for (int i = 0; i < nt; i++) pthread_join(th[i], NULL);
  int bad = ens_hooks_check();
  printf("%d members on %d threads: %s\n", n_members, nt, bad ? "DIFFERENT from one thread" : "same as one thread");
  return bad;
}
