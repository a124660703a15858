!> The public Fortran API of vci in one module: `use vci`.
module vci
  use vci_kinds, only: dp, i8
  use vci_status
  use vci_message, only: VCI_MSG_CUT
  use vci_model_base, only: vci_model_base_t
  use vci_model, only: vci_model_t
  use vci_lagrangian, only: vci_lagrangian_t
  use vci_model_check, only: vci_check_model, vci_check_report_t, vci_check_item_t, VCI_CHECK_DEFAULT_TOL
  use vci_separable, only: vci_separable_t
  use vci_observer, only: vci_observer_t, vci_run_info_t, vci_impact_t
  use vci_progress, only: vci_progress_t, vci_progress_info_t
  use vci_checkpoint, only: vci_checkpoint_t, VCI_CHECKPOINT_VERSION
  use vci_integrator, only: vci_integrator_t, vci_stats_t, vci_settings_t, VCI_IMPACT_DISCRETE, VCI_IMPACT_HAMILTONIAN, &
                            VCI_IMPACT_BLENDED, &
                            VCI_SCHEME_DISCRETE, VCI_SCHEME_LEFT, VCI_SCHEME_MIDPOINT, VCI_SCHEME_LOBATTO, &
                            VCI_LOBATTO_MAX_STAGES, vci_scheme_name, VCI_SCHEME_COMPOSITION, VCI_COMPOSITION_ORDERS
  use vci_newton, only: vci_newton_t, vci_newton_result_t, vci_system_t, NEWTON_CONVERGED, &
                        NEWTON_MAX_ITERATIONS, NEWTON_NO_DESCENT, NEWTON_SINGULAR, NEWTON_EVALUATION, &
                        NEWTON_NONFINITE, NEWTON_STRUCTURE
  use vci_csv_output, only: vci_csv_writer_t
  use vci_sparse, only: vci_sparse_pattern_t, vci_sparse_available => sparse_available
  implicit none
  public
  !> Library version: major*10000 + minor*100 + patch (as vci_version() in C).
  integer, parameter :: VCI_VERSION_NUMBER = 200
end module vci
