!> The settings of a run's solver and impacts, and the solver's counters: plain data shared by the
!> stepper (which holds the one settings object) and the driver (which validates and reports them).
module vci_settings
  use vci_kinds, only: dp, i8
  use vci_message, only: vci_int_text, vci_real_text
  use vci_scheme, only: VCI_IMPACT_DISCRETE
  implicit none
  private

  !> Solver and impact settings: one object, held by the stepper; the driver changes it through
  !> `configure`, which hands Newton and the scheme their part once per change (never per step).
  type, public :: vci_settings_t
    real(dp) :: atol = 0.0_dp            !< absolute floor of Newton's per-row tolerance
    real(dp) :: rtol = 1.0e-12_dp        !< Newton tolerance relative to the size of each row's terms
    integer :: max_iterations = 30       !< Newton iteration cap per solve
    !> Beyond this: VCI_ERR_TOO_MANY_IMPACTS (contact, chatter, a Zeno-like sequence). Until
    !> set_max_impacts chooses it, create sets it from the model: vci_default_max_impacts(n_gaps).
    integer :: max_impacts_per_step = 16
    logical :: max_impacts_chosen = .false. !< set_max_impacts chose it (create keeps it then)
    integer :: impact_energy = VCI_IMPACT_DISCRETE  !< VCI_IMPACT_DISCRETE or VCI_IMPACT_HAMILTONIAN
    !> set_impact_energy chose it: the explicit compositions follow it then, else keep the hamiltonian
    !> condition (docs/SCHEMES.md, "The discrete condition for the compositions")
    logical :: impact_energy_chosen = .false.
    !> The safety net (docs/DESIGN.md §2, "Steps that cannot be solved"): a step whose impacts or
    !> Newton fail is retried as 2, 4, ... equal sub-steps of the same scheme, up to this many;
    !> 1 turns the net off (the step then fails with its own status).
    integer :: max_step_splits = 16
    !> Impact stages solved by bordering the sub-step's block (vci_bordered); false: the whole
    !> stage matrix is factorised (the comparison path of tests and benchmarks).
    logical :: bordered_impacts = .true.
    integer :: border_min = 16     !< ... for stage systems of at least this many unknowns
    !> Sample sub-steps inside for a wall poked within one (docs/BACKWARD.md, "A wall poked within
    !> one sub-step"): set_poke_samples; on by default (off: the gaps at the sub-steps' ends only);
    !> used only where the sub-step resolves the motion (samples_are_path); the explicit
    !> compositions' dip screen follows it (vci_explicit_step)
    logical :: poke_samples = .true.
  end type vci_settings_t

  public :: vci_default_max_impacts, vci_too_many_impacts_cause
  public :: vci_start_beyond_cause, vci_crossed_unseen_cause

  !> Cumulative solver statistics.
  type, public :: vci_solver_stats_t
    integer(i8) :: newton_solves = 0      !< Newton solves
    integer(i8) :: newton_iterations = 0  !< their iterations
    integer(i8) :: fallbacks = 0          !< least-squares fallbacks (singular Newton matrices)
    integer(i8) :: fused_solves = 0   !< of newton_solves, those the scheme's fused routine did
    integer(i8) :: energy_fallbacks = 0  !< soft impacts off the discrete condition: E_d blended with H, or H kept
    !> impacts whose condition could not be tied to the next wall's sub-step, free steps with a
    !> poke seen from their end only (vci_impacts: poke_seen_from_end), and touches whose arriving
    !> momentum leaves the wall (poke_departure)
    integer(i8) :: irreversible_impacts = 0
    integer(i8) :: split_steps = 0       !< steps the safety net took as equal sub-steps
    integer(i8) :: largest_split = 0     !< the most sub-steps one of them needed
  end type vci_solver_stats_t
contains

  !> The default bound on impacts in one step for a model with n_gaps walls (docs/DESIGN.md §2,
  !> "Several impacts in one step"): max(16, 4 n_gaps). A step may meet every wall (a chain of n
  !> particles between walls: 2n gaps, a wave reaching them together), and a wall more than once
  !> (a corner, a bounce back); 16 covers the few walls of small scenes. Beyond it the step fails
  !> (and the safety net retries it in parts, each with the same bound).
  pure integer function vci_default_max_impacts(n_gaps) result(bound)
    integer, intent(in) :: n_gaps
    bound = max(16, 4 * n_gaps)
  end function vci_default_max_impacts

  !> The cause of VCI_ERR_TOO_MANY_IMPACTS: the bound, what reaches it and how to raise it (the
  !> driver puts the step and the time before it).
  pure function vci_too_many_impacts_cause(bound) result(cause)
    integer, intent(in) :: bound
    character(len=:), allocatable :: cause
    character(len=16) :: b
    write (b, '(i0)') bound
    cause = 'more than '//trim(b)//' impacts in one step (the bound; contact, chatter or impacts '// &
            'accumulating at one time; set_max_impacts raises it)'
  end function vci_too_many_impacts_cause
  !> The cause of a step that starts beyond wall j (gap g, beyond the solver's tolerance) although
  !> the step before ended there with every gap >= 0 (VCI_ERR_INADMISSIBLE; the implicit and the
  !> explicit steps say it alike).
  function vci_start_beyond_cause(j, g) result(cause)
    integer, intent(in) :: j
    real(dp), intent(in) :: g
    character(len=:), allocatable :: cause
    cause = 'the step starts beyond wall '//trim(vci_int_text(j))//' (g = '//trim(vci_real_text(g, '(es10.3)'))// &
            ', where the gap callback gave g >= 0 when the step before ended there): a gap that is not a '// &
            'function of q alone, or a model changed under the integrator'
  end function vci_start_beyond_cause

  !> The cause of stage 1's miss: it reached wall `reached` (where: '' or ' at the step''s end') at a
  !> point beyond wall j (gap g), which the motion crossed first (VCI_ERR_IMPACT).
  function vci_crossed_unseen_cause(reached, where, j, g) result(cause)
    integer, intent(in) :: reached, j
    character(len=*), intent(in) :: where
    real(dp), intent(in) :: g
    character(len=:), allocatable :: cause
    cause = 'stage 1 reached wall '//trim(vci_int_text(reached))//where//' at a point beyond wall '// &
            trim(vci_int_text(j))//' (g = '//trim(vci_real_text(g, '(es10.3)'))//'): the motion crossed it first, unseen'
  end function vci_crossed_unseen_cause
end module vci_settings
