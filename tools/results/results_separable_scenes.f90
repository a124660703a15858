!> The results scenes whose Lagrangian is separable, L = ½ q̇ᵀ M q̇ − V(q) with a constant M, written
!> as vci_separable_t so that the explicit compositions (VCI_SCHEME_COMPOSITION) run them: the
!> particle on the floor, the ellipse on the floor (M = diag(m (a² + b²)/4, m, m); only the gap is
!> nonlinear) and the FPU-β chain between walls. The walled pendulum's separable form is
!> examples/scenes/vci_scene_pendulum_walls_sep. Same parameters, gaps and energies as the scenes'
!> other models (vci_results_common).
module results_separable_scenes
  use vci, only: dp, vci_separable_t
  use vci_results_common, only: mass, grav, ell_a, ell_b, fpu_n, fpu_beta, fpu_w
  implicit none
  private

  !> Particle on the floor: q = (x, y), V = m g y, gap y.
  type, extends(vci_separable_t), public :: particle_sep_t
  contains
    procedure :: potential => particle_v, potential_gradient => particle_dv
    procedure :: gaps => particle_gaps, gap_gradients => particle_dg
  end type particle_sep_t

  !> Ellipse on the floor: q = (θ, x, y), V = m g y, gap y − sqrt(a² sin²θ + b² cos²θ).
  type, extends(vci_separable_t), public :: ellipse_sep_t
  contains
    procedure :: potential => ellipse_v, potential_gradient => ellipse_dv
    procedure :: gaps => ellipse_gaps, gap_gradients => ellipse_dg
  end type ellipse_sep_t

  !> FPU-β chain, unit masses, fixed ends: V = Σ_j r_j²/2 + β r_j⁴/4 over the n + 1 stretches;
  !> walls |x_i| <= w (gaps w − x_i, then w + x_i).
  type, extends(vci_separable_t), public :: fpu_sep_t
  contains
    procedure :: potential => fpu_v, potential_gradient => fpu_dv
    procedure :: gaps => fpu_gaps, gap_gradients => fpu_dg
    procedure :: gap_gradient => fpu_dg_one   ! one wall's, O(n): the chain has 2n walls
  end type fpu_sep_t

  public :: particle_sep_model, ellipse_sep_model, fpu_sep_model

contains

  function particle_sep_model() result(model)
    type(particle_sep_t) :: model
    integer :: stat
    model%n = 2; model%n_gaps = 1
    call model%set_mass_diagonal([mass, mass], stat)
  end function particle_sep_model

  function ellipse_sep_model() result(model)
    type(ellipse_sep_t) :: model
    integer :: stat
    model%n = 3; model%n_gaps = 1
    call model%set_mass_diagonal([mass * (ell_a**2 + ell_b**2) / 4.0_dp, mass, mass], stat)
  end function ellipse_sep_model

  function fpu_sep_model() result(model)
    type(fpu_sep_t) :: model
    integer :: stat
    model%n = fpu_n; model%n_gaps = 2 * fpu_n
    call model%set_mass_diagonal(spread(1.0_dp, 1, fpu_n), stat)
  end function fpu_sep_model

  subroutine particle_v(self, q, v, stat)
    class(particle_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: v
    integer, intent(inout) :: stat
    v = mass * grav * q(2)
  end subroutine particle_v

  subroutine particle_dv(self, q, dv, stat)
    class(particle_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dv(:)
    integer, intent(inout) :: stat
    dv(1) = 0.0_dp; dv(2) = mass * grav
  end subroutine particle_dv

  subroutine particle_gaps(self, q, g, stat)
    class(particle_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    g(1) = q(2)
  end subroutine particle_gaps

  subroutine particle_dg(self, q, dg, stat)
    class(particle_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    dg(:, 1) = [0.0_dp, 1.0_dp]
  end subroutine particle_dg

  subroutine ellipse_v(self, q, v, stat)
    class(ellipse_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: v
    integer, intent(inout) :: stat
    v = mass * grav * q(3)
  end subroutine ellipse_v

  subroutine ellipse_dv(self, q, dv, stat)
    class(ellipse_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dv(:)
    integer, intent(inout) :: stat
    dv = [0.0_dp, 0.0_dp, mass * grav]
  end subroutine ellipse_dv

  subroutine ellipse_gaps(self, q, g, stat)
    class(ellipse_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    g(1) = q(3) - sqrt(ell_a**2 * sin(q(1))**2 + ell_b**2 * cos(q(1))**2)
  end subroutine ellipse_gaps

  subroutine ellipse_dg(self, q, dg, stat)
    class(ellipse_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    real(dp) :: phi
    phi = sqrt(ell_a**2 * sin(q(1))**2 + ell_b**2 * cos(q(1))**2)
    dg(:, 1) = [-(ell_a**2 - ell_b**2) * sin(q(1)) * cos(q(1)) / phi, 0.0_dp, 1.0_dp]
  end subroutine ellipse_dg

  !> The n + 1 stretches r_0 = x_1, r_i = x_{i+1} − x_i, r_n = −x_n.
  pure function stretches(x) result(r)
    real(dp), intent(in) :: x(:)
    real(dp) :: r(0:size(x))
    integer :: n
    n = size(x)
    r(0) = x(1); r(1:n - 1) = x(2:n) - x(1:n - 1); r(n) = -x(n)
  end function stretches

  subroutine fpu_v(self, q, v, stat)
    class(fpu_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: v
    integer, intent(inout) :: stat
    real(dp) :: r(0:size(q))
    r = stretches(q)
    v = sum(0.5_dp * r**2 + 0.25_dp * fpu_beta * r**4)
  end subroutine fpu_v

  !> ∂V/∂x_i = V'(r_{i−1}) − V'(r_i), V'(r) = r + β r³.
  subroutine fpu_dv(self, q, dv, stat)
    class(fpu_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dv(:)
    integer, intent(inout) :: stat
    real(dp) :: r(0:size(q)), f(0:size(q))
    integer :: n
    n = size(q)
    r = stretches(q)
    f = r + fpu_beta * r**3
    dv = f(0:n - 1) - f(1:n)
  end subroutine fpu_dv

  subroutine fpu_gaps(self, q, g, stat)
    class(fpu_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    integer :: n
    n = size(q)
    g(1:n) = fpu_w - q
    g(n + 1:2 * n) = fpu_w + q
  end subroutine fpu_gaps

  subroutine fpu_dg(self, q, dg, stat)
    class(fpu_sep_t), intent(inout) :: self
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
  end subroutine fpu_dg

  subroutine fpu_dg_one(self, q, j, dg, stat)
    class(fpu_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    integer, intent(in) :: j
    real(dp), intent(out) :: dg(:)
    integer, intent(inout) :: stat
    integer :: n
    n = size(q)
    dg = 0.0_dp
    if (j <= n) then
      dg(j) = -1.0_dp
    else
      dg(j - n) = 1.0_dp
    end if
  end subroutine fpu_dg_one
end module results_separable_scenes
