!> Regular and impact steps through two separate procedures, so that callgrind can count each kind
!> on its own (`--toggle-collect='*counted_regular_step*'` or `'*counted_impact_step*'`; throughput's
!> --profile-steps). A separate file keeps the compiler from inlining them into the caller.
module vci_bench_split
  use vci, only: vci_integrator_t, i8
  implicit none
  private
  public :: counted_regular_step, counted_impact_step, counted_steps
contains
  !> One step that the first pass found free of impacts.
  subroutine counted_regular_step(integ, stat)
    type(vci_integrator_t), intent(inout) :: integ
    integer, intent(out) :: stat
    call integ%step(1, stat)
  end subroutine counted_regular_step

  !> One step that the first pass found to have an impact.
  subroutine counted_impact_step(integ, stat)
    type(vci_integrator_t), intent(inout) :: integ
    integer, intent(out) :: stat
    call integ%step(1, stat)
  end subroutine counted_impact_step

  !> nsteps steps in one call (`--toggle-collect='*counted_steps*'`: a run without impacts).
  subroutine counted_steps(integ, nsteps, stat)
    type(vci_integrator_t), intent(inout) :: integ
    integer(i8), intent(in) :: nsteps
    integer, intent(out) :: stat
    call integ%integrate(nsteps, 1, stat)
  end subroutine counted_steps
end module vci_bench_split
