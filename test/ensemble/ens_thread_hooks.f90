!> Hooks that let plain POSIX threads (test/ensemble/helgrind_driver.c) run ensemble members the way
!> the OpenMP loop does: every thread calls vci_ensemble_run_member on the same factory,
!> configuration, table and results. Helgrind understands POSIX threads fully, which it does not
!> libgomp's futex-based barriers, so this is the form in which the library's thread safety is checked.
!> With `racy`, every member's model also counts its calls in one unsynchronised module variable:
!> a deliberate race that the checker must report.
module vci_ens_thread_hooks
  use, intrinsic :: iso_c_binding, only: c_int
  use vci
  use vci_ensemble
  use vci_scene_ellipse, only: ellipse_t, ellipse_model
  use vci_ens_test_support
  implicit none
  private

  type, extends(ellipse_t) :: racy_ellipse_t
  contains
    procedure :: d1 => racy_d1
  end type racy_ellipse_t

  type, extends(vci_model_factory_t) :: racy_factory_t
  contains
    procedure :: build => racy_build
  end type racy_factory_t

  type(test_factory_t), save :: factory
  type(racy_factory_t), save :: racy_factory
  type(vci_ensemble_config_t), save :: cfg
  type(vci_ensemble_table_t), save :: table
  type(vci_ensemble_results_t), save :: results
  logical, save :: with_race = .false.
  integer, save :: shared_calls = 0      !< written by every racy model: the deliberate race

  public :: ens_hooks_setup, ens_hooks_run, ens_hooks_check

contains

  !> Build the ensemble (members of every kind, two of them failing); returns the member count.
  integer(c_int) function ens_hooks_setup(racy) bind(C, name='ens_hooks_setup') result(nm)
    integer(c_int), value :: racy
    character(len=VCI_MSG_LEN) :: msg
    integer :: stat
    with_race = racy /= 0
    table = ellipse_table([0.0_dp, 1.0e-12_dp, 1.0e-8_dp, 1.0e-6_dp, 1.0e-4_dp, 0.0_dp, 1.0e-3_dp, 1.0e-2_dp], &
                          [KIND_ELLIPSE, KIND_ELLIPSE, KIND_CALLBACK_FAILS, KIND_ELLIPSE, KIND_ELLIPSE, &
                           KIND_FACTORY_FAILS, KIND_ELLIPSE, KIND_ELLIPSE], 1.0e-2_dp, 100)
    table%q0(3, 5) = 0.1_dp                    ! a start below the floor: a failure message is written
    cfg%h = 1.0e-2_dp; cfg%nsteps = 120; cfg%stride = 10; cfg%impact_cap = 8; cfg%threads = 1
    nm = size(table%t0)
    call vci_ensemble_results_alloc(results, cfg, 3, 1, nm, stat, msg)
    if (stat /= VCI_OK) nm = -1
  end function ens_hooks_setup

  !> Run one member (called concurrently from several threads).
  subroutine ens_hooks_run(member) bind(C, name='ens_hooks_run')
    integer(c_int), value :: member
    if (with_race) then
      call vci_ensemble_run_member(racy_factory, cfg, table, int(member), results)
    else
      call vci_ensemble_run_member(factory, cfg, table, int(member), results)
    end if
  end subroutine ens_hooks_run

  !> 0 when the threads' results are bitwise those of a one-thread vci_ensemble_run, else 1.
  integer(c_int) function ens_hooks_check() bind(C, name='ens_hooks_check') result(bad)
    type(vci_ensemble_results_t) :: ref
    character(len=:), allocatable :: why
    integer :: stat
    bad = 1
    if (with_race) then
      call vci_ensemble_run(racy_factory, cfg, table, ref, stat)
    else
      call vci_ensemble_run(factory, cfg, table, ref, stat)
    end if
    if (stat /= VCI_OK) return
    if (.not. results_identical(results, ref, why)) then
      print '(a)', 'threads and one-thread run differ in '//why
      return
    end if
    if (count(results%status /= VCI_OK) /= 3) then
      print '(a)', 'expected 3 failing members'
      return
    end if
    bad = 0
  end function ens_hooks_check

  subroutine racy_d1(self, q, v, h, out, stat)
    class(racy_ellipse_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    shared_calls = shared_calls + 1
    call self%ellipse_t%d1(q, v, h, out, stat)
  end subroutine racy_d1

  subroutine racy_build(self, member, params, model, stat)
    class(racy_factory_t), intent(in) :: self
    integer, intent(in) :: member
    real(dp), intent(in) :: params(:)
    class(vci_model_t), allocatable, intent(out) :: model
    integer, intent(inout) :: stat
    type(racy_ellipse_t) :: e
    if (nint(params(1)) /= KIND_ELLIPSE) then      ! the failing kinds as usual
      call factory%build(member, params, model, stat)
      return
    end if
    e%ellipse_t = ellipse_model()
    allocate (model, source=e)
  end subroutine racy_build
end module vci_ens_thread_hooks
