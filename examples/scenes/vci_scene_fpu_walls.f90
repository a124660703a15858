!> An FPU-beta chain between walls as a user-written discrete Lagrangian: n unit masses with
!> displacements x_1..x_n, fixed ends x_0 = x_{n+1} = 0, springs V(r) = r^2/2 + beta r^4/4 on the
!> stretches r_j = x_{j+1} - x_j (j = 0..n); midpoint L_d(q, v, h) = h [ |v - q|^2/(2h^2)
!> - V_total((q + v)/2) ]. Walls on every particle, |x_i| <= w: gaps g_i = w - x_i and
!> g_{n+i} = w + x_i (2n of them). Many degrees of freedom, many walls, nonlinear free flight.
!> Reference: test/support/vci_ref_fpu_walls.f90. Used by tools/results.
module vci_scene_fpu_walls
  use vci_kinds, only: dp
  use vci_model, only: vci_model_t
  implicit none
  private

  type, extends(vci_model_t), public :: fpu_walls_t
    real(dp) :: beta = 1.0_dp, w = 0.6_dp
  contains
    procedure :: d1, d2, d3, mixed_hessian, gaps, gap_gradients, energy
  end type fpu_walls_t

  public :: fpu_walls_model

contains

  function fpu_walls_model(n, beta, w) result(model)
    integer, intent(in) :: n
    real(dp), intent(in) :: beta, w
    type(fpu_walls_t) :: model
    model%n = n; model%n_gaps = 2 * n
    model%beta = beta; model%w = w
  end function fpu_walls_model

  !> Stretches r_0..r_n of the chain at x.
  pure function stretches(x) result(r)
    real(dp), intent(in) :: x(:)
    real(dp) :: r(0:size(x))
    integer :: n
    n = size(x)
    r(0) = x(1)
    r(1:n - 1) = x(2:n) - x(1:n - 1)
    r(n) = -x(n)
  end function stretches

  !> Gradient of the potential: dV/dx_i = V'(r_{i-1}) - V'(r_i), V'(r) = r + beta r^3.
  pure function grad_v(self, x) result(gv)
    class(fpu_walls_t), intent(in) :: self
    real(dp), intent(in) :: x(:)
    real(dp) :: gv(size(x)), r(0:size(x)), f(0:size(x))
    integer :: n
    n = size(x)
    r = stretches(x)
    f = r + self%beta * r**3
    gv = f(0:n - 1) - f(1:n)
  end function grad_v

  subroutine d1(self, q, v, h, out, stat)
    class(fpu_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = -(v - q) / h - 0.5_dp * h * grad_v(self, 0.5_dp * (q + v))
  end subroutine d1

  subroutine d2(self, q, v, h, out, stat)
    class(fpu_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = (v - q) / h - 0.5_dp * h * grad_v(self, 0.5_dp * (q + v))
  end subroutine d2

  subroutine d3(self, q, v, h, out, stat)
    class(fpu_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out
    integer, intent(inout) :: stat
    real(dp) :: r(0:size(q))
    r = stretches(0.5_dp * (q + v))
    out = -0.5_dp * sum((v - q)**2) / h**2 - sum(0.5_dp * r**2 + 0.25_dp * self%beta * r**4)
  end subroutine d3

  !> D1 D2 L_d = -I/h - (h/4) Hess V(midpoint), Hess V tridiagonal with K_j = 1 + 3 beta r_j^2.
  subroutine mixed_hessian(self, q, v, h, hess, stat)
    class(fpu_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: hess(:, :)
    integer, intent(inout) :: stat
    real(dp) :: k(0:size(q))
    integer :: i, n
    n = size(q)
    k = 1.0_dp + 3.0_dp * self%beta * stretches(0.5_dp * (q + v))**2
    hess = 0.0_dp
    do i = 1, n
      hess(i, i) = -1.0_dp / h - 0.25_dp * h * (k(i - 1) + k(i))
      if (i < n) then
        hess(i, i + 1) = 0.25_dp * h * k(i)
        hess(i + 1, i) = 0.25_dp * h * k(i)
      end if
    end do
  end subroutine mixed_hessian

  subroutine gaps(self, q, g, stat)
    class(fpu_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    integer :: n
    n = size(q)
    g(1:n) = self%w - q
    g(n + 1:2 * n) = self%w + q
  end subroutine gaps

  subroutine gap_gradients(self, q, dg, stat)
    class(fpu_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    integer :: i, n
    n = size(q)
    dg = 0.0_dp
    do i = 1, n
      dg(i, i) = -1.0_dp
      dg(i, n + i) = 1.0_dp
    end do
  end subroutine gap_gradients

  !> H(q, p) = |p|^2/2 + sum_j (r_j^2/2 + beta r_j^4/4).
  subroutine energy(self, q, p, e, stat)
    class(fpu_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    real(dp) :: r(0:size(q))
    r = stretches(q)
    e = 0.5_dp * sum(p**2) + sum(0.5_dp * r**2 + 0.25_dp * self%beta * r**4)
  end subroutine energy
end module vci_scene_fpu_walls
