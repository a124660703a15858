!> Issue 28 items 1 and 3: with a declared Hessian band no n x n array exists. The FPU-beta chain of
!> n = 20000 (bandwidth 1, the model's banded Hessians) takes regular steps and impact steps under a
!> virtual-memory limit (the ctest runs it under `ulimit -v`, 1 GB): one dense (n + 1)^2 matrix
!> would be 3.2 GB, so an n x n allocation anywhere on the step's path fails create/init/integrate
!> with VCI_ERR_MEMORY (seen with the stepper reserving Newton's dense matrices for every system).
!> Three runs: two walls on the first mass (midpoint); walls |q_i| <= w on every mass, n_gaps = 2n,
!> where a table of every wall's gradient (n x n_gaps, 6.4 GB) fails (seen with the stepper's
!> gap_grads, the composition's grads and the integrator's probe, each n x n_gaps); and those walls
!> with the explicit composition of order 2 (a separable chain). Only the first mass meets a wall.
!> The runs must also be right: the Hamiltonian impact condition keeps H across each impact to the
!> solver's tolerance (the composition's mirror exactly) and the schemes' energy error over the
!> regular steps is O(h^2) of the moving part, so |E - E0| <= 1e-6 |E0| bounds them (observed
!> 7e-8 for the midpoint runs, printed).
module band_memory_model
  use vci
  use vci_scene_fpu_walls, only: fpu_walls_lagrangian_t
  implicit none
  private

  !> The chain with walls |q_1| <= w on the first mass only.
  type, extends(fpu_walls_lagrangian_t), public :: first_mass_walls_t
  contains
    procedure :: gaps => fm_gaps, gap_gradients => fm_gap_grads, gap_gradient => fm_gap_grad
  end type first_mass_walls_t

  !> The separable chain (unit masses, V = sum r^2/2 + beta r^4/4 over the stretches) with walls
  !> |q_i| <= w on every mass, one wall's gradient at a time only, its Hessians on the band 1 (the
  !> integrator builds the midpoint at create: with no band that is n x n).
  type, extends(vci_separable_t), public :: sep_chain_walls_t
    real(dp) :: beta = 1.0_dp, w = 0.6_dp
  contains
    procedure :: potential => sc_v, potential_gradient => sc_dv
    procedure :: gaps => sc_gaps, gap_gradient => sc_gap_grad, hessians_band => sc_hessians_band
  end type sep_chain_walls_t

contains

  subroutine fm_gaps(self, q, g, stat)
    class(first_mass_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    g(1) = self%w - q(1); g(2) = self%w + q(1)
  end subroutine fm_gaps

  subroutine fm_gap_grads(self, q, dg, stat)
    class(first_mass_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    dg = 0.0_dp
    dg(1, 1) = -1.0_dp; dg(1, 2) = 1.0_dp
  end subroutine fm_gap_grads

  subroutine fm_gap_grad(self, q, j, dg, stat)
    class(first_mass_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    integer, intent(in) :: j
    real(dp), intent(out) :: dg(:)
    integer, intent(inout) :: stat
    dg = 0.0_dp
    dg(1) = merge(-1.0_dp, 1.0_dp, j == 1)
  end subroutine fm_gap_grad

  subroutine sc_v(self, q, v, stat)
    class(sep_chain_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: v
    integer, intent(inout) :: stat
    real(dp) :: r(0:size(q))
    r(0) = q(1); r(1:size(q) - 1) = q(2:) - q(:size(q) - 1); r(size(q)) = -q(size(q))
    v = sum(0.5_dp * r**2 + 0.25_dp * self%beta * r**4)
  end subroutine sc_v

  subroutine sc_dv(self, q, dv, stat)
    class(sep_chain_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dv(:)
    integer, intent(inout) :: stat
    real(dp) :: f(0:size(q)), r(0:size(q))
    r(0) = q(1); r(1:size(q) - 1) = q(2:) - q(:size(q) - 1); r(size(q)) = -q(size(q))
    f = r + self%beta * r**3                 ! dV/dr
    dv = f(0:size(q) - 1) - f(1:size(q))     ! r_{i-1} grows with q_i, r_i shrinks
  end subroutine sc_dv

  !> L = |v|^2 / 2 - V on the band: L_qq = -V'' (stiffness k = 1 + 3 beta r^2 of each stretch),
  !> L_vv = 1, L_qv = 0; entry (i, j) at row bw + 1 + i - j of column j.
  subroutine sc_hessians_band(self, q, v, bw, lqq, lqv, lvv, stat)
    class(sep_chain_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:)
    integer, intent(in) :: bw
    real(dp), intent(out) :: lqq(:, :), lqv(:, :), lvv(:, :)
    integer, intent(inout) :: stat
    real(dp) :: r(0:size(q)), k(0:size(q))
    integer :: i, n
    n = size(q)
    r(0) = q(1); r(1:n - 1) = q(2:) - q(:n - 1); r(n) = -q(n)
    k = 1.0_dp + 3.0_dp * self%beta * r**2
    lqq = 0.0_dp; lqv = 0.0_dp; lvv = 0.0_dp
    do i = 1, n
      lqq(bw + 1, i) = -(k(i - 1) + k(i))
      if (i < n) then
        lqq(bw, i + 1) = k(i); lqq(bw + 2, i) = k(i)
      end if
      lvv(bw + 1, i) = 1.0_dp
    end do
  end subroutine sc_hessians_band

  subroutine sc_gaps(self, q, g, stat)
    class(sep_chain_walls_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    g(1:size(q)) = self%w - q
    g(size(q) + 1:) = self%w + q
  end subroutine sc_gaps

  subroutine sc_gap_grad(self, q, j, dg, stat)
    class(sep_chain_walls_t), intent(inout) :: self
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
  end subroutine sc_gap_grad
end module band_memory_model

program band_memory
  use vci
  use vci_scene_fpu_walls, only: fpu_walls_lagrangian_t
  use band_memory_model, only: first_mass_walls_t, sep_chain_walls_t
  implicit none
  integer, parameter :: n = 20000
  type(first_mass_walls_t), target :: model
  type(fpu_walls_lagrangian_t), target :: every_wall
  type(sep_chain_walls_t), target :: sep
  type(vci_integrator_t) :: integ
  real(dp), allocatable :: q0(:), p0(:)
  real(dp) :: pi
  integer :: stat, i
  character(len=40) :: run
  pi = acos(-1.0_dp)
  allocate (q0(n), p0(n))
  do i = 1, n
    q0(i) = 0.2_dp * sin(2 * pi * i / (n + 1.0_dp))
    p0(i) = 0.3_dp * sin(3 * pi * i / (n + 1.0_dp))
  end do
  q0(1) = 0.595_dp; p0(1) = 2.0_dp          ! the first mass meets its wall in the first step

  run = 'two walls, midpoint'
  model%n = n; model%n_gaps = 2; model%beta = 1.0_dp; model%w = 0.6_dp
  model%band_hessians = .true.; model%dense_hessians = .false.
  call model%declare_bandwidth(1)
  call integ%create(model, 0.01_dp, stat)
  if (stat == VCI_OK) call integ%set_scheme(VCI_SCHEME_MIDPOINT, 1, stat)
  call check_run(model%w, model%beta)

  run = 'walls on every mass, midpoint'
  every_wall%n = n; every_wall%n_gaps = 2 * n; every_wall%beta = 1.0_dp; every_wall%w = 0.6_dp
  every_wall%band_hessians = .true.; every_wall%dense_hessians = .false.
  call every_wall%declare_bandwidth(1)
  call integ%create(every_wall, 0.01_dp, stat)
  if (stat == VCI_OK) call integ%set_scheme(VCI_SCHEME_MIDPOINT, 1, stat)
  call check_run(every_wall%w, every_wall%beta)

  run = 'walls on every mass, composition 2'
  sep%n = n; sep%n_gaps = 2 * n
  call sep%set_mass_diagonal(spread(1.0_dp, 1, n), stat)
  if (stat /= VCI_OK) call fail('mass matrix')
  call sep%declare_bandwidth(1)
  call integ%create(sep, 0.01_dp, stat)
  if (stat == VCI_OK) call integ%set_scheme(VCI_SCHEME_COMPOSITION, 2, stat)
  call check_run(sep%w, sep%beta)
  print '(a)', 'band_memory: passed'
contains
  !> Integrate 40 steps from (q0, p0) with Hamiltonian impacts (integ created, its scheme set: stat)
  !> and check the energy and the first mass's walls.
  subroutine check_run(w, beta)
    real(dp), intent(in) :: w, beta
    type(vci_stats_t) :: st
    real(dp), allocatable :: q(:), p(:)
    real(dp) :: e0, e1
    if (stat == VCI_OK) call integ%set_impact_energy(VCI_IMPACT_HAMILTONIAN, stat)
    if (stat == VCI_OK) call integ%init_from_momentum(0.0_dp, q0, p0, stat)
    if (stat /= VCI_OK) call fail('set-up')
    e0 = chain_energy(q0, p0, beta)
    call integ%integrate(40_i8, 1, stat)
    if (stat /= VCI_OK) call fail('integrate')
    st = integ%statistics()
    q = integ%configuration(); p = integ%momentum()
    e1 = chain_energy(q, p, beta)
    print '(a,i0,a,i0,a,i0,a,es10.2)', 'band_memory ('//trim(run)//'): n = ', n, ', steps ', int(st%steps), &
      ', impacts ', int(st%impacts), ', |E - E0| / |E0| = ', abs(e1 - e0) / abs(e0)
    if (st%impacts < 1) call fail('expected impacts on the first mass''s walls')
    if (.not. abs(e1 - e0) <= 1.0e-6_dp * abs(e0)) call fail('energy not kept')
    if (.not. (abs(q(1)) <= w * (1.0_dp + 1.0e-12_dp))) call fail('the first mass left its walls')
  end subroutine check_run

  !> H = |p|^2 / 2 + sum_j (r_j^2 / 2 + beta r_j^4 / 4), r the stretches q_1, q_{i+1} - q_i, -q_n.
  real(dp) function chain_energy(q, p, beta) result(e)
    real(dp), intent(in) :: q(:), p(:), beta
    real(dp) :: r
    integer :: j
    e = 0.5_dp * sum(p**2)
    do j = 0, n
      if (j == 0) then
        r = q(1)
      else if (j == n) then
        r = -q(n)
      else
        r = q(j + 1) - q(j)
      end if
      e = e + 0.5_dp * r**2 + 0.25_dp * beta * r**4
    end do
  end function chain_energy

  subroutine fail(what)
    character(len=*), intent(in) :: what
    print '(a)', 'band_memory FAILED ('//trim(run)//') at '//what//': '//trim(integ%message())
    error stop 1
  end subroutine fail
end program band_memory
