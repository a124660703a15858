!> The paper's bouncing ellipse: q = (theta, x, y), midpoint L_d with gravity, floor gap
!> g(q) = y - phi(theta), phi = sqrt(a^2 sin^2 theta + b^2 cos^2 theta). docs/DESIGN.md §8.
!> `ellipse_lagrangian_t`: the same body as a continuous model, L = I θ̇²/2 + m(ẋ² + ẏ²)/2 − m g y.
module vci_scene_ellipse
  use vci, only: dp, vci_model_t, vci_lagrangian_t
  implicit none
  private

  type, extends(vci_model_t), public :: ellipse_t
    real(dp) :: mass = 1.0_dp, grav = 9.8_dp, a = 1.0_dp, b = 0.5_dp
    logical :: analytic_hessian = .true.
    !> supply ld_fused (D1, D2, D3 and the Hessian in one call; with analytic_hessian only). Off by
    !> default (tests override d1 alone to make it fail); the examples and the benchmark turn it on
    logical :: fused_callback = .false.
  contains
    procedure :: d1, d2, d3, mixed_hessian, gaps, gap_gradients, energy
    procedure :: ld_fused
    procedure :: inertia
  end type ellipse_t

  type, extends(vci_lagrangian_t), public :: ellipse_lagrangian_t
    real(dp) :: mass = 1.0_dp, grav = 9.8_dp, a = 1.0_dp, b = 0.5_dp
  contains
    procedure :: lagrangian => el_lagrangian, dl_dq => el_dl_dq, dl_dv => el_dl_dv, hessians => el_hessians
    procedure :: gaps => el_gaps, gap_gradients => el_gap_grads, energy => el_energy
  end type ellipse_lagrangian_t

  public :: ellipse_model, ellipse_lagrangian_model

contains

  function ellipse_model() result(model)
    type(ellipse_t) :: model
    model%n = 3; model%n_gaps = 1
  end function ellipse_model

  function ellipse_lagrangian_model() result(model)
    type(ellipse_lagrangian_t) :: model
    model%n = 3; model%n_gaps = 1
  end function ellipse_lagrangian_model

  pure real(dp) function inertia(self)
    class(ellipse_t), intent(in) :: self
    inertia = self%mass * (self%a**2 + self%b**2) / 4.0_dp
  end function inertia

  subroutine d1(self, q, v, h, out, stat)
    class(ellipse_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out(1) = -self%inertia() * (v(1) - q(1)) / h
    out(2) = -self%mass * (v(2) - q(2)) / h
    out(3) = -self%mass * (v(3) - q(3)) / h - 0.5_dp * h * self%mass * self%grav
  end subroutine d1

  subroutine d2(self, q, v, h, out, stat)
    class(ellipse_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out(1) = self%inertia() * (v(1) - q(1)) / h
    out(2) = self%mass * (v(2) - q(2)) / h
    out(3) = self%mass * (v(3) - q(3)) / h - 0.5_dp * h * self%mass * self%grav
  end subroutine d2

  subroutine d3(self, q, v, h, out, stat)
    class(ellipse_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out
    integer, intent(inout) :: stat
    out = -0.5_dp * (self%inertia() * (v(1) - q(1))**2 + self%mass * ((v(2) - q(2))**2 + (v(3) - q(3))**2)) / h**2 &
          - 0.5_dp * self%mass * self%grav * (q(3) + v(3))
  end subroutine d3

  subroutine mixed_hessian(self, q, v, h, hess, stat)
    class(ellipse_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: hess(:, :)
    integer, intent(inout) :: stat
    if (.not. self%analytic_hessian) then
      call self%not_provided(stat); return
    end if
    hess = 0.0_dp
    hess(1, 1) = -self%inertia() / h
    hess(2, 2) = -self%mass / h
    hess(3, 3) = -self%mass / h
  end subroutine mixed_hessian

  !> d1, d2, d3 and mixed_hessian in one call, with the same arithmetic (same bits).
  subroutine ld_fused(self, q, v, h, d1, d2, d3, hess, stat)
    class(ellipse_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: d1(:), d2(:), d3, hess(:, :)
    integer, intent(inout) :: stat
    real(dp) :: in, w1, w2, w3, fall
    if (.not. (self%fused_callback .and. self%analytic_hessian)) then
      call self%not_provided(stat); return
    end if
    in = self%inertia()
    w1 = v(1) - q(1); w2 = v(2) - q(2); w3 = v(3) - q(3)
    fall = 0.5_dp * h * self%mass * self%grav
    d1(1) = -in * w1 / h
    d1(2) = -self%mass * w2 / h
    d1(3) = -self%mass * w3 / h - fall
    d2(1) = in * w1 / h
    d2(2) = self%mass * w2 / h
    d2(3) = self%mass * w3 / h - fall
    d3 = -0.5_dp * (in * w1**2 + self%mass * (w2**2 + w3**2)) / h**2 - 0.5_dp * self%mass * self%grav * (q(3) + v(3))
    hess = 0.0_dp
    hess(1, 1) = -in / h
    hess(2, 2) = -self%mass / h
    hess(3, 3) = -self%mass / h
  end subroutine ld_fused

  subroutine gaps(self, q, g, stat)
    class(ellipse_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    g(1) = q(3) - sqrt(self%a**2 * sin(q(1))**2 + self%b**2 * cos(q(1))**2)
  end subroutine gaps

  subroutine gap_gradients(self, q, dg, stat)
    class(ellipse_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    real(dp) :: phi
    phi = sqrt(self%a**2 * sin(q(1))**2 + self%b**2 * cos(q(1))**2)
    dg(:, 1) = [-(self%a**2 - self%b**2) * sin(q(1)) * cos(q(1)) / phi, 0.0_dp, 1.0_dp]
  end subroutine gap_gradients

  subroutine energy(self, q, p, e, stat)
    class(ellipse_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    e = 0.5_dp * p(1)**2 / self%inertia() + 0.5_dp * (p(2)**2 + p(3)**2) / self%mass + self%mass * self%grav * q(3)
  end subroutine energy
  subroutine el_lagrangian(self, q, v, l, stat)
    class(ellipse_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: l
    integer, intent(inout) :: stat
    l = 0.5_dp * self%mass * (self%a**2 + self%b**2) / 4.0_dp * v(1)**2 + 0.5_dp * self%mass * (v(2)**2 + v(3)**2) &
        - self%mass * self%grav * q(3)
  end subroutine el_lagrangian

  subroutine el_dl_dq(self, q, v, out, stat)
    class(ellipse_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = [0.0_dp, 0.0_dp, -self%mass * self%grav]
  end subroutine el_dl_dq

  subroutine el_dl_dv(self, q, v, out, stat)
    class(ellipse_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out = [self%mass * (self%a**2 + self%b**2) / 4.0_dp * v(1), self%mass * v(2), self%mass * v(3)]
  end subroutine el_dl_dv

  !> Constant blocks: L_qq = L_qv = 0, L_vv = diag(I, m, m).
  subroutine el_hessians(self, q, v, lqq, lqv, lvv, stat)
    class(ellipse_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: lqq(:, :), lqv(:, :), lvv(:, :)
    integer, intent(inout) :: stat
    lqq = 0.0_dp; lqv = 0.0_dp; lvv = 0.0_dp
    lvv(1, 1) = self%mass * (self%a**2 + self%b**2) / 4.0_dp
    lvv(2, 2) = self%mass; lvv(3, 3) = self%mass
  end subroutine el_hessians

  subroutine el_gaps(self, q, g, stat)
    class(ellipse_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    g(1) = q(3) - sqrt(self%a**2 * sin(q(1))**2 + self%b**2 * cos(q(1))**2)
  end subroutine el_gaps

  subroutine el_gap_grads(self, q, dg, stat)
    class(ellipse_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    real(dp) :: phi
    phi = sqrt(self%a**2 * sin(q(1))**2 + self%b**2 * cos(q(1))**2)
    dg(:, 1) = [-(self%a**2 - self%b**2) * sin(q(1)) * cos(q(1)) / phi, 0.0_dp, 1.0_dp]
  end subroutine el_gap_grads

  subroutine el_energy(self, q, p, e, stat)
    class(ellipse_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    e = 0.5_dp * p(1)**2 / (self%mass * (self%a**2 + self%b**2) / 4.0_dp) + 0.5_dp * (p(2)**2 + p(3)**2) / self%mass &
        + self%mass * self%grav * q(3)
  end subroutine el_energy
end module vci_scene_ellipse
