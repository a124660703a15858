!> The Kepler problem as a continuous model, L = |v|²/2 + 1/|q| (n = 2, no walls): a smooth,
!> bounded, strongly nonlinear scene with an exact solution (Kepler's equation) for order tests.
!> Orbit: semi-major axis 1, eccentricity e, start at pericentre, period 2 pi.
module vci_test_kepler
  use vci
  implicit none
  private

  type, extends(vci_lagrangian_t), public :: kepler_t
    logical :: analytic_hessians = .true.
  contains
    procedure :: lagrangian, dl_dq, dl_dv, hessians
  end type kepler_t

  public :: kepler_model, kepler_exact

contains

  function kepler_model() result(model)
    type(kepler_t) :: model
    model%n = 2
  end function kepler_model

  subroutine lagrangian(self, q, v, l, stat)
    class(kepler_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: l
    integer, intent(inout) :: stat
    l = 0.5_dp * sum(v**2) + 1.0_dp / norm2(q)
  end subroutine lagrangian

  subroutine dl_dq(self, q, v, out, stat)
    class(kepler_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = -q / norm2(q)**3
  end subroutine dl_dq

  subroutine dl_dv(self, q, v, out, stat)
    class(kepler_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = v
  end subroutine dl_dv

  subroutine hessians(self, q, v, lqq, lqv, lvv, stat)
    class(kepler_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: lqq(:, :), lqv(:, :), lvv(:, :)
    integer, intent(inout) :: stat
    real(dp) :: r
    integer :: i
    if (.not. self%analytic_hessians) then
      call self%not_provided(stat); return
    end if
    r = norm2(q)
    do i = 1, 2
      lqq(:, i) = 3.0_dp * q * q(i) / r**5
      lqq(i, i) = lqq(i, i) - 1.0_dp / r**3
    end do
    lqv = 0.0_dp
    lvv = 0.0_dp; lvv(1, 1) = 1.0_dp; lvv(2, 2) = 1.0_dp
  end subroutine hessians

  !> Exact state at time t from pericentre (mean anomaly t): Newton on E - e sin E = t.
  subroutine kepler_exact(e, t, q, v)
    real(dp), intent(in) :: e, t
    real(dp), intent(out) :: q(2), v(2)
    real(dp) :: ea, f
    integer :: it
    ea = t
    do it = 1, 100
      f = (ea - e * sin(ea) - t) / (1.0_dp - e * cos(ea))
      ea = ea - f
      if (abs(f) < 1.0e-16_dp * max(1.0_dp, abs(t))) exit
    end do
    q = [cos(ea) - e, sqrt(1.0_dp - e**2) * sin(ea)]
    v = [-sin(ea), sqrt(1.0_dp - e**2) * cos(ea)] / (1.0_dp - e * cos(ea))
  end subroutine kepler_exact
end module vci_test_kepler
