!> Exact reference: a point mass in the (x, y) plane under gravity g (downward), bouncing
!> elastically on the floor y = 0. Independent of the vci library.
module vci_ref_particle
  use iso_fortran_env, only: real64
  implicit none
  private

  integer, parameter :: dp = real64

  public :: particle_exact

contains

  !> State at time t >= 0 of the mass started at (0, y0), y0 >= 0, with velocity (vx0, vy0), g > 0,
  !> and the impact times in (0, t], ascending. Between bounces the motion is a parabola; every
  !> bounce reverses vy with the impact speed s = sqrt(vy0² + 2 g y0) (energy), so after the first
  !> impact t1 the arcs repeat with period 2 s / g. A start on the floor moving down bounces at
  !> t = 0 (not listed); a start at rest on the floor stays there. At an impact time itself the
  !> velocity returned may be either the pre- or the post-impact one.
  subroutine particle_exact(y0, vx0, vy0, g, t, x, y, vx, vy, impact_times, n_impacts)
    real(dp), intent(in) :: y0, vx0, vy0, g, t
    real(dp), intent(out) :: x, y, vx, vy
    real(dp), allocatable, intent(out) :: impact_times(:)
    integer, intent(out) :: n_impacts
    real(dp) :: s, t1, period, tau
    integer :: j, j_first, j_last

    x = vx0*t
    vx = vx0
    s = sqrt(vy0**2 + 2.0_dp*g*y0)
    if (s <= 0.0_dp) then
      y = 0.0_dp
      vy = 0.0_dp
      n_impacts = 0
      allocate (impact_times(0))
      return
    end if
    ! Positive root of y0 + vy0 t - g t²/2, in the form without cancellation.
    if (vy0 >= 0.0_dp) then
      t1 = (vy0 + s)/g
    else
      t1 = 2.0_dp*y0/(s - vy0)
    end if
    if (t < t1) then
      y = y0 + vy0*t - 0.5_dp*g*t**2
      vy = vy0 - g*t
      n_impacts = 0
      allocate (impact_times(0))
      return
    end if

    period = 2.0_dp*s/g
    j_last = floor((t - t1)/period)
    j_first = merge(0, 1, t1 > 0.0_dp)
    n_impacts = max(0, j_last - j_first + 1)
    allocate (impact_times(n_impacts))
    do j = j_first, j_last
      impact_times(j - j_first + 1) = t1 + real(j, dp)*period
    end do
    tau = t - (t1 + real(j_last, dp)*period)
    y = s*tau - 0.5_dp*g*tau**2
    vy = s - g*tau
  end subroutine particle_exact

end module vci_ref_particle
