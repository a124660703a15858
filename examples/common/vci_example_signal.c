/* SIGINT and SIGTERM for the examples' runs (issue 31): the handler only records the signal; the
 * run's progress report sees it after the current step and ends the run cleanly (the file is
 * flushed and closed, its status says it was interrupted). SA_RESETHAND: a second signal of the
 * same kind acts as if no handler were installed (a second Ctrl-C ends a hung run at once).
 * The library installs no handler: only these programs do. */
#include <signal.h>
#include <string.h>

static volatile sig_atomic_t caught = 0;

static void on_signal(int sig)
{
    caught = sig;
}

/* Install the handler for SIGINT and SIGTERM; 0 on success. */
int vci_example_catch_signals(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESETHAND;
    if (sigaction(SIGINT, &sa, NULL) != 0) return -1;
    if (sigaction(SIGTERM, &sa, NULL) != 0) return -1;
    return 0;
}

/* The signal caught so far (SIGINT = 2, SIGTERM = 15), or 0. */
int vci_example_signal_caught(void)
{
    return caught;
}
