!> Downstream check: the bouncing ellipse at h = 1e-2 through `use vci` from the installed
!> modules; stops with code 1 unless 2 impacts happen in 2 s, the first at the expected time.
module downstream_ellipse
  use vci, only: vci_model_t, dp
  implicit none
  private
  !> Only the required procedures and the gaps: the library differences the rest.
  type, extends(vci_model_t), public :: ellipse_t
    real(dp) :: mass = 1.0_dp, grav = 9.8_dp, a = 1.0_dp, b = 0.5_dp
  contains
    procedure :: d1, d2, d3, gaps
  end type ellipse_t
contains
  pure real(dp) function inertia(self)
    class(ellipse_t), intent(in) :: self
    inertia = self%mass * (self%a**2 + self%b**2) / 4.0_dp
  end function inertia
  subroutine d1(self, q, v, h, out, stat)
    class(ellipse_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = [-inertia(self) * (v(1) - q(1)) / h, -self%mass * (v(2) - q(2)) / h, &
           -self%mass * (v(3) - q(3)) / h - 0.5_dp * h * self%mass * self%grav]
  end subroutine d1
  subroutine d2(self, q, v, h, out, stat)
    class(ellipse_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = [inertia(self) * (v(1) - q(1)) / h, self%mass * (v(2) - q(2)) / h, &
           self%mass * (v(3) - q(3)) / h - 0.5_dp * h * self%mass * self%grav]
  end subroutine d2
  subroutine d3(self, q, v, h, out, stat)
    class(ellipse_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out
    integer, intent(inout) :: stat
    out = -0.5_dp * (inertia(self) * (v(1) - q(1))**2 + self%mass * ((v(2) - q(2))**2 + (v(3) - q(3))**2)) / h**2 &
          - 0.5_dp * self%mass * self%grav * (q(3) + v(3))
  end subroutine d3
  subroutine gaps(self, q, g, stat)
    class(ellipse_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    g(1) = q(3) - sqrt(self%a**2 * sin(q(1))**2 + self%b**2 * cos(q(1))**2)
  end subroutine gaps
end module downstream_ellipse

program ellipse_modern
  use vci
  use downstream_ellipse, only: ellipse_t
  implicit none
  !> the first impact from the Fortran API with analytic derivatives (differenced ones converge to the
  !> same root: the Newton tolerance 1e-12 bounds the difference)
  real(dp), parameter :: t_ref = 7.50564104356950312e-01_dp
  type(ellipse_t), target :: model
  type(vci_integrator_t) :: integ
  real(dp) :: h, q0(3), qd(3), t_first
  type(vci_impact_t) :: first
  type(vci_stats_t) :: stats
  integer :: stat, i
  h = 1.0e-2_dp
  model%n = 3; model%n_gaps = 1
  q0 = [acos(-1.0_dp) / 2.0_dp, 0.0_dp, 3.5_dp]
  qd = [-3.0_dp, 2.0_dp, 0.0_dp]
  call integ%create(model, h, stat)
  if (stat == VCI_OK) call integ%set_tolerances(0.0_dp, 1.0e-12_dp, 30, stat)
  if (stat == VCI_OK) call integ%init_from_pair(-0.5_dp * h, q0 - 0.5_dp * h * qd, q0 + 0.5_dp * h * qd, stat)
  t_first = -1.0_dp
  do i = 1, 200
    if (stat /= VCI_OK) exit
    call integ%step(1, stat)
    if (integ%impact_count() > 0 .and. t_first < 0.0_dp) then
      first = integ%impact(1); t_first = first%t
    end if
  end do
  stats = integ%statistics()
  print '(a,i0,a,i0,a,f18.15,a,es8.1)', 'status ', stat, ', impacts ', stats%impacts, ', first at t = ', &
    t_first, ', off by ', abs(t_first - t_ref)
  if (stat /= VCI_OK .or. stats%impacts /= 2 .or. .not. abs(t_first - t_ref) <= 1.0e-12_dp &
      .or. abs(integ%time() - 2.005_dp) > 1.0e-13_dp) then
    print '(a)', 'FAILED: '//integ%message()
    stop 1
  end if
  print '(a)', 'passed'
end program ellipse_modern
