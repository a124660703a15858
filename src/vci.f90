!> The public Fortran API of vci in one module: `use vci`.
module vci
  use vci_kinds, only: dp, i8
  use vci_status
  use vci_model, only: vci_model_t
  use vci_observer, only: vci_observer_t, vci_run_info_t, vci_impact_t
  use vci_integrator, only: vci_integrator_t, vci_stats_t, vci_checkpoint_t, VCI_IMPACT_DISCRETE, VCI_IMPACT_HAMILTONIAN
  use vci_newton, only: vci_newton_t, vci_newton_result_t, vci_system_t, NEWTON_CONVERGED, &
                        NEWTON_MAX_ITERATIONS, NEWTON_NO_DESCENT, NEWTON_SINGULAR, NEWTON_EVALUATION, &
                        NEWTON_NONFINITE
  use vci_csv_output, only: vci_csv_writer_t
  implicit none
  public
  !> Library version: major*10000 + minor*100 + patch (as vci_version() in C).
  integer, parameter :: VCI_VERSION_NUMBER = 200
end module vci
