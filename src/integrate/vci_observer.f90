!> The observer interface: the integrator reports every accepted step and every impact to it,
!> so output formats (CSV, HDF5, in-memory recorders) are not the stepper's business.
!> All procedures have empty defaults; extend the type and override what you need. Set `stat`
!> nonzero to stop the run (reported as VCI_ERR_IO by the integrator, with `failure_cause`;
!> VCI_ERR_MEMORY stays VCI_ERR_MEMORY: an output with no memory for a checkpoint).
!>
!> Checkpoints: an observer that stores them (keeps_checkpoints) does not know the driver; the driver
!> hands it one (on_checkpoint) when the observer asks (wants_checkpoint is true before the report
!> that will store it), before on_start, and always before on_finish (docs/DESIGN.md, layers).
module vci_observer
  use vci_kinds, only: dp, i8
  use vci_checkpoint, only: vci_checkpoint_t
  implicit none
  private

  !> What an observer learns when a run starts.
  type, public :: vci_run_info_t
    integer :: n = 0                    !< configuration dimension
    integer :: m = 0                    !< number of constraints
    integer :: n_gaps = 0               !< number of walls
    integer :: direction = 1            !< +1 forward, -1 backward
    real(dp) :: h = 0.0_dp              !< step length
    real(dp) :: t0 = 0.0_dp             !< time of index 0 (t = t0 + k h)
    integer(i8) :: step0 = 0_i8         !< index of the starting state
    integer :: impact_energy = 0        !< VCI_IMPACT_DISCRETE or VCI_IMPACT_HAMILTONIAN
    integer :: scheme = 0               !< VCI_SCHEME_* of the run (0: not known)
    integer :: stages = 0               !< set_scheme's stages: s of lobatto, the order of composition, 1 for left/midpoint, 0: L_d
    real(dp) :: rtol = 0.0_dp           !< Newton tolerance relative to the size of each row's terms
    real(dp) :: atol = 0.0_dp           !< absolute floor of Newton's per-row tolerance
    integer :: max_impacts = 0          !< impacts allowed in one step
    integer :: start = 0                !< how the run started: 0 not known, 1 (q0, q1) pair, 2 (q0, p0), 3 a checkpoint
  end type vci_run_info_t

  !> One impact, as resolved by stages 1 and 2.
  type, public :: vci_impact_t
    real(dp) :: t = 0.0_dp              !< impact time t_k + alpha h (forward) or t_k+1 - beta h (backward)
    integer(i8) :: step = 0_i8          !< index of the state the step started from
    real(dp) :: alpha = 0.0_dp          !< fraction of the step, from its start in the direction of motion
    integer :: gap = 0                  !< index j of the wall reached
    real(dp) :: impulse = 0.0_dp        !< normal impulse: p_after - p_before = impulse * grad g_j (forward time)
    real(dp), allocatable :: q(:)       !< the configuration on the wall
    real(dp), allocatable :: p_before(:)  !< momentum at the wall before the impact, in the direction of motion
    real(dp), allocatable :: p_after(:)   !< momentum at the wall after the impact, in the direction of motion
    real(dp), allocatable :: grad_g(:)  !< gradient of the gap at q
    !> The impact condition that fixed the impulse: the integrator's setting; near a graze under the
    !> discrete condition (0), VCI_IMPACT_BLENDED (2, E_d blended with H) or, as a last resort,
    !> VCI_IMPACT_HAMILTONIAN (1) (docs/DESIGN.md §2)
    integer :: condition = 0
    !> E_d of the arriving sub-step, H(q, p_before) (condition 1) or w E_d + (1 - w) H (condition 2)
    real(dp) :: energy_before = 0.0_dp
    !> E_d of the leaving sub-step, H(q, p_after) (condition 1) or w E_d + (1 - w) H (condition 2)
    real(dp) :: energy_after = 0.0_dp
    real(dp) :: leave_rate = 0.0_dp     !< grad g . (q_next - q) / sub-step: > 0, the motion leaves the wall
    real(dp) :: stage1_residual = 0.0_dp  !< stage 1's scaled residual (<= 1 means within tolerance)
    real(dp) :: stage2_residual = 0.0_dp  !< stage 2's scaled residual (<= 1 means within tolerance)
  end type vci_impact_t

  !> Receives every step and impact of a run: extend it and override what you need (module doc).
  type, public :: vci_observer_t
  contains
    !> The run starts from (t0, q, p).
    procedure :: on_start => default_on_start
    !> An accepted step: state index `step`, time t, (q, p), multipliers lambda and the discrete energy E_d.
    procedure :: on_step => default_on_step
    !> An impact inside the step that is about to be reported by on_step.
    procedure :: on_impact => default_on_impact
    !> The step that is about to be reported (its impacts, then on_step) was taken as `parts` equal
    !> sub-steps by the safety net (set_step_splits); not called for a step taken whole.
    procedure :: on_split => default_on_split
    !> The run ended with `status` (VCI_OK or an error) and its message.
    procedure :: on_finish => default_on_finish
    !> Does this observer store checkpoints, so that a run continues from its output bit for bit? (default: no)
    procedure :: keeps_checkpoints => default_keeps_checkpoints
    !> Does the next report store a checkpoint? Then the driver calls on_checkpoint first (default: no).
    procedure :: wants_checkpoint => default_wants_checkpoint
    !> The driver's checkpoint of the state the next report (on_start, on_step, on_finish) is about.
    procedure :: on_checkpoint => default_on_checkpoint
    !> Why the last report set `stat` nonzero (a message naming the file and the cause; default: blank).
    procedure :: failure_cause => default_failure_cause
  end type vci_observer_t

contains

  !> The run starts from (t0, q, p).
  subroutine default_on_start(self, info, q, p, stat)
    class(vci_observer_t), intent(inout) :: self
    type(vci_run_info_t), intent(in) :: info
    real(dp), intent(in) :: q(:), p(:)
    integer, intent(inout) :: stat
  end subroutine default_on_start

  !> An accepted step: state index `step`, time t, (q, p), multipliers lambda (size m) and the
  !> discrete energy E_d of the step (of its last sub-step when it had impacts).
  subroutine default_on_step(self, step, t, q, p, lambda, energy, stat)
    class(vci_observer_t), intent(inout) :: self
    integer(i8), intent(in) :: step
    real(dp), intent(in) :: t, q(:), p(:), lambda(:), energy
    integer, intent(inout) :: stat
  end subroutine default_on_step

  !> An impact inside the step that is about to be reported by on_step.
  subroutine default_on_impact(self, impact, stat)
    class(vci_observer_t), intent(inout) :: self
    type(vci_impact_t), intent(in) :: impact
    integer, intent(inout) :: stat
  end subroutine default_on_impact

  !> The step from index `step` that is about to be reported was taken as `parts` equal sub-steps
  !> (the safety net, set_step_splits); not called for a step taken whole.
  subroutine default_on_split(self, step, parts, stat)
    class(vci_observer_t), intent(inout) :: self
    integer(i8), intent(in) :: step
    integer, intent(in) :: parts
    integer, intent(inout) :: stat
  end subroutine default_on_split

  !> Does this observer store checkpoints (vci_checkpoint), so that a run continues from its output
  !> bit for bit? No, unless an output says so.
  pure logical function default_keeps_checkpoints(self)
    class(vci_observer_t), intent(in) :: self
    default_keeps_checkpoints = .false.
  end function default_keeps_checkpoints

  !> Does the next report (on_start, or the on_step after the impacts already reported) store a
  !> checkpoint? Then the driver calls on_checkpoint with the state that report is about, first.
  pure logical function default_wants_checkpoint(self)
    class(vci_observer_t), intent(in) :: self
    default_wants_checkpoint = .false.
  end function default_wants_checkpoint

  !> The driver's checkpoint of the state the next report (on_start, on_step, on_finish) is about.
  subroutine default_on_checkpoint(self, cp, stat)
    class(vci_observer_t), intent(inout) :: self
    type(vci_checkpoint_t), intent(in) :: cp
    integer, intent(inout) :: stat
  end subroutine default_on_checkpoint

  !> Why the last report set `stat` nonzero (e.g. the file and the OS's reason), or blank.
  subroutine default_failure_cause(self, cause)
    class(vci_observer_t), intent(in) :: self
    character(len=*), intent(out) :: cause
    cause = ''
  end subroutine default_failure_cause

  !> The run ended with `status` (VCI_OK or an error) and its message.
  subroutine default_on_finish(self, status, message, stat)
    class(vci_observer_t), intent(inout) :: self
    integer, intent(in) :: status
    character(len=*), intent(in) :: message
    integer, intent(inout) :: stat
  end subroutine default_on_finish
end module vci_observer
