!> The paper's nonholonomic spherical pendulum in a cylinder: q = (theta, phi),
!> L_d(q, v, h) = m l^2/(2h) ((v_th - th)^2 + (v_ph - ph)^2 sin^2 th) - h m g l cos th (anchored at q),
!> constraint form omega = f(theta) dtheta - dphi with f = pi + cos^2 theta, discrete constraint
!> omega_d(q, v, h) = (f(theta)(v_th - th) - (v_ph - ph)) / h, and the cylinder wall
!> g = R^2 - l^2 sin^2 theta >= 0 (docs/DESIGN.md §8: the paper's l sin theta <= R stops binding past pi).
!> `pendulum_lagrangian_t` is the same scene as a continuous model, L = ½ m l² (θ̇² + sin²θ φ̇²) − m g l cos θ,
!> with Ω = f(θ) dθ − dφ: the `left` scheme turns it into the L_d above.
module vci_scene_pendulum
  use vci, only: dp, vci_model_t, vci_lagrangian_t
  implicit none
  private

  real(dp), parameter :: pi = acos(-1.0_dp)

  type, extends(vci_model_t), public :: pendulum_t
    real(dp) :: mass = 1.0_dp, grav = 9.8_dp, length = 2.0_dp, radius = 1.5_dp
    logical :: analytic_hessian = .true.   !< supply the mixed Hessian and the constraint Jacobian (else differenced)
    !> supply ld_fused (D1, D2, D3 and the Hessian in one call, one sine and cosine; with analytic_hessian
    !> only). Off by default (tests override d1 alone); the examples and the benchmark turn it on
    logical :: fused_callback = .false.
  contains
    procedure :: d1, d2, d3, mixed_hessian, constraint_forms, discrete_constraint, gaps, gap_gradients, energy
    procedure :: ld_fused
    procedure :: discrete_constraint_jacobian
  end type pendulum_t

  !> The continuous model (a few lines: L, its partials and Hessians, Omega, the wall, H).
  type, extends(vci_lagrangian_t), public :: pendulum_lagrangian_t
    real(dp) :: mass = 1.0_dp, grav = 9.8_dp, length = 2.0_dp, radius = 1.5_dp
  contains
    procedure :: lagrangian => pl_lagrangian, dl_dq => pl_dl_dq, dl_dv => pl_dl_dv, hessians => pl_hessians
    procedure :: constraint_forms => pl_forms, gaps => pl_gaps, gap_gradients => pl_gap_grads, energy => pl_energy
  end type pendulum_lagrangian_t

  public :: pendulum_model, pendulum_f, pendulum_lagrangian_model

contains

  function pendulum_model() result(model)
    type(pendulum_t) :: model
    model%n = 2; model%m = 1; model%n_gaps = 1
  end function pendulum_model

  function pendulum_lagrangian_model() result(model)
    type(pendulum_lagrangian_t) :: model
    model%n = 2; model%m = 1; model%n_gaps = 1
  end function pendulum_lagrangian_model

  elemental real(dp) function pendulum_f(theta)
    real(dp), intent(in) :: theta
    pendulum_f = pi + cos(theta)**2
  end function pendulum_f

  subroutine d1(self, q, v, h, out, stat)
    class(pendulum_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    real(dp) :: ml2, s, c
    ml2 = self%mass * self%length**2; s = sin(q(1)); c = cos(q(1))
    out(1) = -ml2 * (v(1) - q(1)) / h + ml2 * (v(2) - q(2))**2 * s * c / h + h * self%mass * self%grav * self%length * s
    out(2) = -ml2 * (v(2) - q(2)) * s**2 / h
  end subroutine d1

  subroutine d2(self, q, v, h, out, stat)
    class(pendulum_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    real(dp) :: ml2
    ml2 = self%mass * self%length**2
    out(1) = ml2 * (v(1) - q(1)) / h
    out(2) = ml2 * (v(2) - q(2)) * sin(q(1))**2 / h
  end subroutine d2

  subroutine d3(self, q, v, h, out, stat)
    class(pendulum_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out
    integer, intent(inout) :: stat
    out = -0.5_dp * self%mass * self%length**2 * ((v(1) - q(1))**2 + (v(2) - q(2))**2 * sin(q(1))**2) / h**2 &
          - self%mass * self%grav * self%length * cos(q(1))
  end subroutine d3

  subroutine mixed_hessian(self, q, v, h, hess, stat)
    class(pendulum_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: hess(:, :)
    integer, intent(inout) :: stat
    real(dp) :: ml2, s, c
    if (.not. self%analytic_hessian) then
      call self%not_provided(stat); return
    end if
    ml2 = self%mass * self%length**2; s = sin(q(1)); c = cos(q(1))
    hess(1, 1) = -ml2 / h
    hess(1, 2) = 2.0_dp * ml2 * (v(2) - q(2)) * s * c / h
    hess(2, 1) = 0.0_dp
    hess(2, 2) = -ml2 * s**2 / h
  end subroutine mixed_hessian

  !> d1, d2, d3 and mixed_hessian in one call, one sine and cosine, the same arithmetic (same bits).
  subroutine ld_fused(self, q, v, h, d1, d2, d3, hess, stat)
    class(pendulum_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: d1(:), d2(:), d3, hess(:, :)
    integer, intent(inout) :: stat
    real(dp) :: ml2, s, c, w1, w2
    if (.not. (self%fused_callback .and. self%analytic_hessian)) then
      call self%not_provided(stat); return
    end if
    ml2 = self%mass * self%length**2; s = sin(q(1)); c = cos(q(1))
    w1 = v(1) - q(1); w2 = v(2) - q(2)
    d1(1) = -ml2 * w1 / h + ml2 * w2**2 * s * c / h + h * self%mass * self%grav * self%length * s
    d1(2) = -ml2 * w2 * s**2 / h
    d2(1) = ml2 * w1 / h
    d2(2) = ml2 * w2 * s**2 / h
    d3 = -0.5_dp * self%mass * self%length**2 * (w1**2 + w2**2 * s**2) / h**2 - self%mass * self%grav * self%length * c
    hess(1, 1) = -ml2 / h
    hess(1, 2) = 2.0_dp * ml2 * w2 * s * c / h
    hess(2, 1) = 0.0_dp
    hess(2, 2) = -ml2 * s**2 / h
  end subroutine ld_fused

  subroutine constraint_forms(self, q, omega, stat)
    class(pendulum_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: omega(:, :)
    integer, intent(inout) :: stat
    omega(:, 1) = [pendulum_f(q(1)), -1.0_dp]
  end subroutine constraint_forms

  subroutine discrete_constraint(self, base, other, h, out, stat)
    class(pendulum_t), intent(inout) :: self
    real(dp), intent(in) :: base(:), other(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out(1) = (pendulum_f(base(1)) * (other(1) - base(1)) - (other(2) - base(2))) / h
  end subroutine discrete_constraint

  !> d omega_d(base, other, h) / d other (1 x 2).
  subroutine discrete_constraint_jacobian(self, base, other, h, jac, stat)
    class(pendulum_t), intent(inout) :: self
    real(dp), intent(in) :: base(:), other(:), h
    real(dp), intent(out) :: jac(:, :)
    integer, intent(inout) :: stat
    if (.not. self%analytic_hessian) then
      call self%not_provided(stat); return
    end if
    jac(1, 1) = pendulum_f(base(1)) / h
    jac(1, 2) = -1.0_dp / h
  end subroutine discrete_constraint_jacobian

  subroutine gaps(self, q, g, stat)
    class(pendulum_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    g(1) = self%radius**2 - self%length**2 * sin(q(1))**2
  end subroutine gaps

  subroutine gap_gradients(self, q, dg, stat)
    class(pendulum_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    dg(:, 1) = [-2.0_dp * self%length**2 * sin(q(1)) * cos(q(1)), 0.0_dp]
  end subroutine gap_gradients

  !> H = p_th^2/(2 m l^2) + p_ph^2/(2 m l^2 sin^2 th) + m g l cos th; singular at sin th = 0, which
  !> the walls (|sin th| = R/l there) never reach, and H is only evaluated on a wall.
  subroutine energy(self, q, p, e, stat)
    class(pendulum_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    real(dp) :: ml2, s2
    ml2 = self%mass * self%length**2; s2 = sin(q(1))**2
    if (sqrt(s2) <= 4.0_dp * epsilon(1.0_dp)) then   ! sin theta = 0 to round-off: H undefined
      stat = 1; e = 0.0_dp; return
    end if
    e = 0.5_dp * p(1)**2 / ml2 + 0.5_dp * p(2)**2 / (ml2 * s2) + self%mass * self%grav * self%length * cos(q(1))
  end subroutine energy
  subroutine pl_lagrangian(self, q, v, l, stat)
    class(pendulum_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: l
    integer, intent(inout) :: stat
    l = 0.5_dp * self%mass * self%length**2 * (v(1)**2 + sin(q(1))**2 * v(2)**2) &
        - self%mass * self%grav * self%length * cos(q(1))
  end subroutine pl_lagrangian

  subroutine pl_dl_dq(self, q, v, out, stat)
    class(pendulum_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out(1) = self%mass * self%length**2 * sin(q(1)) * cos(q(1)) * v(2)**2 + self%mass * self%grav * self%length * sin(q(1))
    out(2) = 0.0_dp
  end subroutine pl_dl_dq

  subroutine pl_dl_dv(self, q, v, out, stat)
    class(pendulum_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    out(1) = self%mass * self%length**2 * v(1)
    out(2) = self%mass * self%length**2 * sin(q(1))**2 * v(2)
  end subroutine pl_dl_dv

  subroutine pl_hessians(self, q, v, lqq, lqv, lvv, stat)
    class(pendulum_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    real(dp), intent(out) :: lqq(:, :), lqv(:, :), lvv(:, :)
    integer, intent(inout) :: stat
    real(dp) :: ml2, s, c
    ml2 = self%mass * self%length**2; s = sin(q(1)); c = cos(q(1))
    lqq = 0.0_dp; lqv = 0.0_dp; lvv = 0.0_dp
    lqq(1, 1) = ml2 * (c**2 - s**2) * v(2)**2 + self%mass * self%grav * self%length * c
    lqv(1, 2) = 2.0_dp * ml2 * s * c * v(2)
    lvv(1, 1) = ml2
    lvv(2, 2) = ml2 * s**2
  end subroutine pl_hessians

  subroutine pl_forms(self, q, omega, stat)
    class(pendulum_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: omega(:, :)
    integer, intent(inout) :: stat
    omega(:, 1) = [pendulum_f(q(1)), -1.0_dp]
  end subroutine pl_forms

  subroutine pl_gaps(self, q, g, stat)
    class(pendulum_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    g(1) = self%radius**2 - self%length**2 * sin(q(1))**2
  end subroutine pl_gaps

  subroutine pl_gap_grads(self, q, dg, stat)
    class(pendulum_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    dg(:, 1) = [-2.0_dp * self%length**2 * sin(q(1)) * cos(q(1)), 0.0_dp]
  end subroutine pl_gap_grads

  !> H as for the discrete model (undefined at sin theta = 0, never reached on the wall).
  subroutine pl_energy(self, q, p, e, stat)
    class(pendulum_lagrangian_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    real(dp) :: ml2, s2
    ml2 = self%mass * self%length**2; s2 = sin(q(1))**2
    if (sqrt(s2) <= 4.0_dp * epsilon(1.0_dp)) then
      stat = 1; e = 0.0_dp; return
    end if
    e = 0.5_dp * p(1)**2 / ml2 + 0.5_dp * p(2)**2 / (ml2 * s2) + self%mass * self%grav * self%length * cos(q(1))
  end subroutine pl_energy
end module vci_scene_pendulum
