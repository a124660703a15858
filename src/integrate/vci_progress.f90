!> Progress of a long run (issue 31): integrate(..., progress=p) calls p%report(info, stop_requested) at most
!> once per p%interval seconds of wall time (and after the last step); setting `stop_requested` ends the
!> run cleanly after the current step with VCI_STOPPED (the state is that step's; the observer's
!> on_finish hears VCI_STOPPED, so an output file is flushed and closed and says so). The library
!> prints nothing itself: the examples' --progress prints the line (examples/common).
module vci_progress
  use vci_kinds, only: dp, i8
  implicit none
  private

  !> What a progress report knows: steps done of this call and its total, the model time, impacts
  !> so far (all calls), wall time of this call, rate and estimated time left (-1: unknown yet).
  type, public :: vci_progress_info_t
    integer(i8) :: steps_done = 0          !< steps done in this integrate call
    integer(i8) :: steps_total = 0         !< steps this call was asked for
    integer(i8) :: impacts = 0             !< impacts so far (all calls)
    real(dp) :: t = 0.0_dp                 !< model time of the current state
    real(dp) :: elapsed = 0.0_dp           !< wall seconds of this call
    real(dp) :: steps_per_second = 0.0_dp  !< rate so far
    real(dp) :: eta = -1.0_dp              !< estimated wall seconds left (-1: unknown yet)
  end type vci_progress_info_t

  !> Extend and override report; pass it to integrate (progress=).
  type, abstract, public :: vci_progress_t
    real(dp) :: interval = 0.5_dp   !< seconds of wall time between reports (0: after every step)
  contains
    !> Called at most once per interval and after the last step (interface report_iface).
    procedure(report_iface), deferred :: report
  end type vci_progress_t

  abstract interface
    !> A progress report: `info` says where the run is; set `stop_requested` to end the run after this step.
    subroutine report_iface(self, info, stop_requested)
      import :: vci_progress_t, vci_progress_info_t
      class(vci_progress_t), intent(inout) :: self
      type(vci_progress_info_t), intent(in) :: info
      logical, intent(inout) :: stop_requested   !< .false. on entry; .true.: end the run after this step
    end subroutine report_iface
  end interface
end module vci_progress
