!> The bench's other separable scenes for the composition step (bench/composition.f90): the FPU-β
!> chain (n = 32 unit masses, fixed ends, V = Σ r²/2 + β r⁴/4 over the 33 stretches) and the Kepler
!> problem (n = 2, V = −1/|q|, M = I), both without walls. The force of each is one explicit-shape
!> routine that the model's callback and the bench's hand-written loop both call, so the two runs
!> do the same arithmetic and end in the same bits. Also the timed library calls (here, in their
!> own file, so that the compiler cannot fold them into the set-up around them: callgrind's
!> --toggle-collect='*run_timed*' then counts the run alone).
module vci_bench_composition_scenes
  use, intrinsic :: iso_fortran_env, only: int64
  use vci, only: dp, i8, VCI_OK, vci_separable_t, vci_integrator_t
  implicit none
  private

  integer, parameter, public :: chain_n = 32
  real(dp), parameter, public :: chain_beta = 1.0_dp

  type, extends(vci_separable_t), public :: chain_sep_t
  contains
    procedure :: potential => chain_v, potential_gradient => chain_dv
  end type chain_sep_t

  type, extends(vci_separable_t), public :: kepler_sep_t
  contains
    procedure :: potential => kepler_v, potential_gradient => kepler_dv
  end type kepler_sep_t

  !> The chain between walls at ±chain_wall (issue 32 item 1: stage 1 on a large chain), with a
  !> count of its gradient callbacks (the composed maps' stages: the cost of an impact).
  type, extends(chain_sep_t), public :: chain_walls_sep_t
    integer(i8) :: gradient_calls = 0
  contains
    procedure :: potential_gradient => chain_walls_dv
    procedure :: gaps => chain_walls_gaps, gap_gradients => chain_walls_dg
    procedure :: gap_gradient => chain_walls_dg_one
  end type chain_walls_sep_t
  real(dp), parameter, public :: chain_wall = 0.6_dp

  public :: chain_gradient, kepler_gradient, chain_sep_model, kepler_sep_model, run_timed_integrate, run_timed_steps
  public :: chain_walls_sep_model

contains

  function chain_sep_model() result(model)
    type(chain_sep_t) :: model
    integer :: stat
    model%n = chain_n; model%n_gaps = 0
    call model%set_mass_diagonal(spread(1.0_dp, 1, chain_n), stat)
  end function chain_sep_model

  function kepler_sep_model() result(model)
    type(kepler_sep_t) :: model
    integer :: stat
    model%n = 2; model%n_gaps = 0
    call model%set_mass_diagonal([1.0_dp, 1.0_dp], stat)
  end function kepler_sep_model

  !> n particles between walls at ±chain_wall (2n gaps), unit masses.
  function chain_walls_sep_model(n) result(model)
    integer, intent(in) :: n
    type(chain_walls_sep_t) :: model
    integer :: stat
    model%n = n; model%n_gaps = 2 * n
    call model%set_mass_diagonal(spread(1.0_dp, 1, n), stat)
  end function chain_walls_sep_model

  subroutine chain_walls_dv(self, q, dv, stat)
    class(chain_walls_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dv(:)
    integer, intent(inout) :: stat
    self%gradient_calls = self%gradient_calls + 1
    call chain_gradient(size(q), q, dv)
  end subroutine chain_walls_dv

  !> g_i = w − x_i, g_{n+i} = w + x_i.
  subroutine chain_walls_gaps(self, q, g, stat)
    class(chain_walls_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    integer :: n
    n = size(q)
    g(1:n) = chain_wall - q
    g(n + 1:2 * n) = chain_wall + q
  end subroutine chain_walls_gaps

  subroutine chain_walls_dg(self, q, dg, stat)
    class(chain_walls_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    integer :: i, n
    n = size(q)
    dg = 0.0_dp
    do i = 1, n
      dg(i, i) = -1.0_dp; dg(i, n + i) = 1.0_dp
    end do
  end subroutine chain_walls_dg

  subroutine chain_walls_dg_one(self, q, j, dg, stat)
    class(chain_walls_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    integer, intent(in) :: j
    real(dp), intent(out) :: dg(:)
    integer, intent(inout) :: stat
    dg = 0.0_dp
    if (j <= size(q)) then
      dg(j) = -1.0_dp
    else
      dg(j - size(q)) = 1.0_dp
    end if
  end subroutine chain_walls_dg_one

  !> dv_i = V'(r_{i−1}) − V'(r_i), V'(r) = r + β r³, r_0 = x_1, r_i = x_{i+1} − x_i, r_n = −x_n.
  pure subroutine chain_gradient(n, x, dv)
    integer, intent(in) :: n
    real(dp), intent(in) :: x(n)
    real(dp), intent(out) :: dv(n)
    real(dp) :: r, f_left, f_right
    integer :: i
    r = x(1); f_left = r + chain_beta * r**3
    do i = 1, n
      if (i < n) then
        r = x(i + 1) - x(i)
      else
        r = -x(n)
      end if
      f_right = r + chain_beta * r**3
      dv(i) = f_left - f_right
      f_left = f_right
    end do
  end subroutine chain_gradient

  !> ∇V = q / |q|³.
  pure subroutine kepler_gradient(q, dv)
    real(dp), intent(in) :: q(2)
    real(dp), intent(out) :: dv(2)
    real(dp) :: r2, r3
    r2 = q(1)**2 + q(2)**2
    r3 = r2 * sqrt(r2)
    dv(1) = q(1) / r3; dv(2) = q(2) / r3
  end subroutine kepler_gradient

  subroutine chain_v(self, q, v, stat)
    class(chain_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: v
    integer, intent(inout) :: stat
    real(dp) :: r(0:size(q))
    r(0) = q(1); r(1:size(q) - 1) = q(2:) - q(:size(q) - 1); r(size(q)) = -q(size(q))
    v = sum(0.5_dp * r**2 + 0.25_dp * chain_beta * r**4)
  end subroutine chain_v

  subroutine chain_dv(self, q, dv, stat)
    class(chain_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dv(:)
    integer, intent(inout) :: stat
    call chain_gradient(size(q), q, dv)
  end subroutine chain_dv

  subroutine kepler_v(self, q, v, stat)
    class(kepler_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: v
    integer, intent(inout) :: stat
    v = -1.0_dp / sqrt(q(1)**2 + q(2)**2)
  end subroutine kepler_v

  subroutine kepler_dv(self, q, dv, stat)
    class(kepler_sep_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dv(:)
    integer, intent(inout) :: stat
    call kepler_gradient(q, dv)
  end subroutine kepler_dv
  !> integrate(n, forward) alone: what the instruction counts (*run_timed*) and times measure
  !> of a library run (the integrator's set-up is outside).
  subroutine run_timed_integrate(integ, n, stat, elapsed)
    type(vci_integrator_t), intent(inout) :: integ
    integer(i8), intent(in) :: n
    integer, intent(out) :: stat
    real(dp), intent(out) :: elapsed
    elapsed = wall_clock()
    call integ%integrate(n, 1, stat)
    elapsed = wall_clock() - elapsed
  end subroutine run_timed_integrate

  !> n calls of step(forward), as a caller stepping one by one.
  subroutine run_timed_steps(integ, n, stat, elapsed)
    type(vci_integrator_t), intent(inout) :: integ
    integer, intent(in) :: n
    integer, intent(out) :: stat
    real(dp), intent(out) :: elapsed
    integer :: k
    elapsed = wall_clock()
    stat = VCI_OK
    do k = 1, n
      call integ%step(1, stat)
      if (stat /= VCI_OK) exit
    end do
    elapsed = wall_clock() - elapsed
  end subroutine run_timed_steps

  real(dp) function wall_clock()
    integer(int64) :: c, r
    call system_clock(c, r)
    wall_clock = real(c, dp) / real(r, dp)
  end function wall_clock
end module vci_bench_composition_scenes
