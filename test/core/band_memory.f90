!> Issue 28 items 1 and 3: with a declared Hessian band no n x n array exists. The FPU-beta chain of
!> n = 20000 (bandwidth 1, the model's banded Hessians, two walls on the first mass so the impact
!> buffers stay O(n)) takes regular steps and impact steps under a virtual-memory limit (the ctest
!> runs it under `ulimit -v`, 1 GB): one dense (n + 1)^2 matrix would be 3.2 GB, so an n x n
!> allocation anywhere on the step's path fails create/init/integrate with VCI_ERR_MEMORY (seen with
!> the stepper reserving Newton's dense matrices for every system). The run must also be right:
!> the Hamiltonian impact condition keeps H across each impact to the solver's tolerance and the
!> midpoint rule's energy error over the regular steps is O(h^2), so |E - E0| <= 1e-6 |E0| bounds
!> both here (observed 7e-8, printed).
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
end module band_memory_model

program band_memory
  use vci
  use band_memory_model, only: first_mass_walls_t
  implicit none
  integer, parameter :: n = 20000
  type(first_mass_walls_t), target :: model
  type(vci_integrator_t) :: integ
  type(vci_stats_t) :: st
  real(dp), allocatable :: q0(:), p0(:), q(:), p(:)
  real(dp) :: e0, e1, pi
  integer :: stat, i
  pi = acos(-1.0_dp)
  model%n = n; model%n_gaps = 2; model%beta = 1.0_dp; model%w = 0.6_dp
  model%band_hessians = .true.; model%dense_hessians = .false.
  call model%declare_bandwidth(1)
  allocate (q0(n), p0(n))
  do i = 1, n
    q0(i) = 0.2_dp * sin(2 * pi * i / (n + 1.0_dp))
    p0(i) = 0.3_dp * sin(3 * pi * i / (n + 1.0_dp))
  end do
  q0(1) = 0.595_dp; p0(1) = 2.0_dp          ! the first mass meets its wall in the first step
  call integ%create(model, 0.01_dp, stat)
  if (stat == VCI_OK) call integ%set_scheme(VCI_SCHEME_MIDPOINT, 1, stat)
  if (stat == VCI_OK) call integ%set_impact_energy(VCI_IMPACT_HAMILTONIAN, stat)
  if (stat == VCI_OK) call integ%init_from_momentum(0.0_dp, q0, p0, stat)
  if (stat /= VCI_OK) call fail('set-up')
  e0 = chain_energy(q0, p0)
  call integ%integrate(40_i8, 1, stat)
  if (stat /= VCI_OK) call fail('integrate')
  st = integ%statistics()
  q = integ%configuration(); p = integ%momentum()
  e1 = chain_energy(q, p)
  print '(a,i0,a,i0,a,i0,a,es10.2)', 'band_memory: n = ', n, ', steps ', int(st%steps), ', impacts ', &
    int(st%impacts), ', |E - E0| / |E0| = ', abs(e1 - e0) / abs(e0)
  if (st%impacts < 1) call fail('expected impacts on the first mass''s walls')
  if (.not. abs(e1 - e0) <= 1.0e-6_dp * abs(e0)) call fail('energy not kept')
  if (.not. (abs(q(1)) <= model%w * (1.0_dp + 1.0e-12_dp))) call fail('the first mass left its walls')
  print '(a)', 'band_memory: passed'
contains
  !> H = |p|^2 / 2 + sum_j (r_j^2 / 2 + beta r_j^4 / 4), r the stretches q_1, q_{i+1} - q_i, -q_n.
  real(dp) function chain_energy(q, p) result(e)
    real(dp), intent(in) :: q(:), p(:)
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
      e = e + 0.5_dp * r**2 + 0.25_dp * model%beta * r**4
    end do
  end function chain_energy

  subroutine fail(what)
    character(len=*), intent(in) :: what
    print '(a)', 'band_memory FAILED at '//what//': '//trim(integ%message())
    error stop 1
  end subroutine fail
end program band_memory
