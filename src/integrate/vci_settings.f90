!> The settings of a run's solver and impacts, and the solver's counters: plain data shared by the
!> stepper (which holds the one settings object) and the driver (which validates and reports them).
module vci_settings
  use vci_kinds, only: dp, i8
  use vci_scheme, only: VCI_IMPACT_DISCRETE
  implicit none
  private

  !> Solver and impact settings: one object, held by the stepper; the driver changes it through
  !> `configure`, which hands Newton and the scheme their part once per change (never per step).
  type, public :: vci_settings_t
    real(dp) :: atol = 0.0_dp            !< absolute floor of Newton's per-row tolerance
    real(dp) :: rtol = 1.0e-12_dp        !< Newton tolerance relative to the size of each row's terms
    integer :: max_iterations = 30       !< Newton iteration cap per solve
    integer :: max_impacts_per_step = 16 !< beyond this: VCI_ERR_TOO_MANY_IMPACTS (contact, chatter)
    integer :: impact_energy = VCI_IMPACT_DISCRETE  !< VCI_IMPACT_DISCRETE or VCI_IMPACT_HAMILTONIAN
    !> The safety net (docs/DESIGN.md §2, "Steps that cannot be solved"): a step whose impacts or
    !> Newton fail is retried as 2, 4, ... equal sub-steps of the same scheme, up to this many;
    !> 1 turns the net off (the step then fails with its own status).
    integer :: max_step_splits = 16
  end type vci_settings_t

  !> Cumulative solver statistics.
  type, public :: vci_solver_stats_t
    integer(i8) :: newton_solves = 0      !< Newton solves
    integer(i8) :: newton_iterations = 0  !< their iterations
    integer(i8) :: fallbacks = 0          !< least-squares fallbacks (singular Newton matrices)
    integer(i8) :: fused_solves = 0   !< of newton_solves, those the scheme's fused routine did
    integer(i8) :: energy_fallbacks = 0  !< soft impacts off the discrete condition: E_d blended with H, or H kept
    integer(i8) :: split_steps = 0       !< steps the safety net took as equal sub-steps
    integer(i8) :: largest_split = 0     !< the most sub-steps one of them needed
  end type vci_solver_stats_t
end module vci_settings
