!> Issue 28 items 1 and 3 for sparse patterns: with a declared pattern and the model's sparse
!> Hessians no n x n array exists. The FPU-beta chain of n = 20000 with long-range springs (i, i + L),
!> L = n / 8 (examples/scenes/vci_scene_long_range_chain.f90: 5 nonzeros a row, but a band of
!> half-width 2500 would hold them: 800 MB of band storage), two walls on the first mass so the
!> impact buffers stay O(n), takes regular and impact steps under a virtual-memory limit (the ctest
!> runs it under `ulimit -v`, 1 GB): one dense (n + 1)^2 matrix would be 3.2 GB, so an n x n
!> allocation anywhere on the step's path fails create/init/integrate with VCI_ERR_MEMORY (seen
!> with the Hessians gathered from the dense callback, and with the Newton matrix assembled densely).
!> The run must also be right: the Hamiltonian impact condition keeps H across each impact to the
!> solver's tolerance and the midpoint rule's energy error over the regular steps is O(h^2), so
!> |E - E0| <= 1e-6 |E0| bounds both here (observed: printed).
module sparse_memory_model
  use vci
  use vci_scene_long_range_chain, only: long_range_chain_t
  implicit none
  private

  !> The long-range chain with walls |q_1| <= w on the first mass only.
  type, extends(long_range_chain_t), public :: first_mass_walls_t
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
end module sparse_memory_model

program sparse_memory
  use vci
  use sparse_memory_model, only: first_mass_walls_t
  implicit none
  integer, parameter :: n = 20000
  type(first_mass_walls_t), target :: model
  type(vci_integrator_t) :: integ
  type(vci_stats_t) :: st
  real(dp), allocatable :: q0(:), p0(:), q(:), p(:)
  real(dp) :: e0, e1, pi
  integer :: stat, i
  if (.not. vci_sparse_available()) then
    print '(a)', 'sparse_memory: passed (skipped: built without VCI_SPARSE)'
    stop
  end if
  pi = acos(-1.0_dp)
  model%n = n; model%n_gaps = 2; model%beta = 1.0_dp; model%w = 0.6_dp; model%offset = n / 8
  model%sparse_hessians = .true.; model%dense_hessians = .false.
  call model%declare_long_range_pattern(.false.)
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
  call model%energy(q0, p0, e0, stat)
  call integ%integrate(40_i8, 1, stat)
  if (stat /= VCI_OK) call fail('integrate')
  st = integ%statistics()
  q = integ%configuration(); p = integ%momentum()
  call model%energy(q, p, e1, stat)
  print '(a,i0,a,i0,a,i0,a,i0,a,es10.2)', 'sparse_memory: n = ', n, ', steps ', int(st%steps), ', impacts ', &
    int(st%impacts), ', sparse Hessian calls ', model%sparse_calls, ', |E - E0| / |E0| = ', abs(e1 - e0) / abs(e0)
  if (st%impacts < 1) call fail('expected impacts on the first mass''s walls')
  if (model%sparse_calls < 1) call fail('expected the sparse Hessian callback to be used')
  if (.not. abs(e1 - e0) <= 1.0e-6_dp * abs(e0)) call fail('energy not kept')
  if (.not. (abs(q(1)) <= model%w * (1.0_dp + 1.0e-12_dp))) call fail('the first mass left its walls')
  print '(a)', 'sparse_memory: passed'
contains
  subroutine fail(what)
    character(len=*), intent(in) :: what
    print '(a)', 'sparse_memory FAILED at '//what//': '//trim(integ%message())
    error stop 1
  end subroutine fail
end program sparse_memory
