!> Test driver for the ensemble file (and, built with MPI, for ranks):
!>   ens_driver run FILE [--members N] [--nsteps K] [--threads T] [--chunk C] [--stride S] [--fail]
!>     runs the test ensemble (perturbed ellipses; with --fail, members 3, 5, 7, 11 fail on purpose)
!>     into FILE with vci_ensemble_run_file (all ranks under mpirun);
!>     Built as ens_alloc_driver (VCI_ENS_MALLOC_FAIL, linked with test/alloc's malloc_counter.c):
!>     --fail-alloc K MIN [--fail-rank R] [--fail-in OBJ] makes the K-th allocation of at least MIN
!>     bytes inside vci_ensemble_run_file fail (on rank R only, default every rank; counting only
!>     those made from the shared object whose path contains OBJ) and prints on each armed rank
!>     whether it was met ("rank r: allocation K failed" / "rank r: allocation K not reached");
!>   ens_driver verify FILE [--partial]
!>     reads FILE, runs every member the file says was run again in memory (one thread) from the
!>     file's own table, and exits 1 unless they are bitwise equal. With --fail members 3, 5, 7, 11
!>     must have their statuses. Without --partial every member must have been run; with it, at
!>     least one must have and at least one must not (a killed run).
program ens_driver
  use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
#ifdef VCI_HAVE_MPI
  use mpi_f08
#endif
  use vci
  use vci_ensemble
  use vci_ensemble_h5, only: vci_ensemble_read
  use vci_ensemble_mpi, only: vci_ensemble_run_file
  use vci_ens_test_support
#ifdef VCI_ENS_MALLOC_FAIL
  use, intrinsic :: iso_c_binding, only: c_long_long, c_char, c_null_char
#endif
  implicit none
#ifdef VCI_ENS_MALLOC_FAIL
  interface
    subroutine vci_test_malloc_fail(k, min_bytes) bind(C, name='vci_test_malloc_fail')
      import :: c_long_long
      integer(c_long_long), value :: k, min_bytes
    end subroutine vci_test_malloc_fail
    subroutine vci_test_malloc_fail_in(k, min_bytes, object) bind(C, name='vci_test_malloc_fail_in')
      import :: c_long_long, c_char
      integer(c_long_long), value :: k, min_bytes
      character(kind=c_char), intent(in) :: object(*)
    end subroutine vci_test_malloc_fail_in
    function vci_test_malloc_fail_pending() bind(C, name='vci_test_malloc_fail_pending') result(k)
      import :: c_long_long
      integer(c_long_long) :: k
    end function vci_test_malloc_fail_pending
  end interface
  integer :: fail_k = 0, fail_min = 0, fail_rank = -1
  character(len=64) :: fail_in = ''
#endif
  character(len=512) :: mode, path, arg
  integer :: nm, nsteps, threads, chunk, stride, i, stat, rank, failed, fail_after
  logical :: with_failures, partial
  type(test_factory_t) :: factory
  type(vci_ensemble_config_t) :: cfg
  type(vci_ensemble_table_t) :: table
  character(len=VCI_MSG_LEN) :: msg
  real(dp), allocatable :: deltas(:)
  integer, allocatable :: kinds(:)
  real(dp), parameter :: h = 1.0e-2_dp
#ifdef VCI_HAVE_MPI
  integer :: provided, ierr
  call MPI_Init_thread(MPI_THREAD_FUNNELED, provided, ierr)
  call MPI_Comm_rank(MPI_COMM_WORLD, rank, ierr)
#else
  rank = 0
#endif
  nm = 40; nsteps = 600; threads = 1; chunk = 0; stride = 0; fail_after = 300
  with_failures = .false.; partial = .false.
  call get_command_argument(1, mode)
  call get_command_argument(2, path)
  i = 3
  do while (i <= command_argument_count())
    call get_command_argument(i, arg)
    select case (arg)
    case ('--members'); nm = int_arg(i + 1); i = i + 1
    case ('--nsteps'); nsteps = int_arg(i + 1); i = i + 1
    case ('--threads'); threads = int_arg(i + 1); i = i + 1
    case ('--chunk'); chunk = int_arg(i + 1); i = i + 1
    case ('--stride'); stride = int_arg(i + 1); i = i + 1
    case ('--fail'); with_failures = .true.
    case ('--partial'); partial = .true.
#ifdef VCI_ENS_MALLOC_FAIL
    case ('--fail-alloc'); fail_k = int_arg(i + 1); fail_min = int_arg(i + 2); i = i + 2
    case ('--fail-rank'); fail_rank = int_arg(i + 1); i = i + 1
    case ('--fail-in'); call get_command_argument(i + 1, fail_in); i = i + 1
#endif
    case default
      print '(a)', 'unknown argument '//trim(arg); call finish(2)
    end select
    i = i + 1
  end do

  select case (mode)
  case ('run')
    allocate (deltas(nm), kinds(nm))
    do i = 1, nm
      deltas(i) = 0.0_dp
      if (i > 1) deltas(i) = 10.0_dp**(-14.0_dp + 12.0_dp * real(i - 2, dp) / real(max(nm - 2, 1), dp))
    end do
    kinds = KIND_ELLIPSE
    fail_after = nsteps                  ! D1 is called more than once a step: fails before the end
    if (with_failures .and. nm >= 11) then
      kinds(7) = KIND_CALLBACK_FAILS; kinds(11) = KIND_FACTORY_FAILS
    end if
    table = ellipse_table(deltas, kinds, h, fail_after)
    if (with_failures .and. nm >= 11) then
      table%q0(1, 3) = ieee_value(1.0_dp, ieee_quiet_nan)         ! a NaN start
      table%q0(3, 5) = 0.1_dp; table%v0(3, 5) = 0.1_dp            ! below the floor
    end if
    cfg%h = h; cfg%nsteps = nsteps; cfg%threads = threads; cfg%chunk = chunk; cfg%stride = stride
    cfg%impact_cap = 32
    cfg%name = 'ens_driver test ensemble'
#ifdef VCI_ENS_MALLOC_FAIL
    if (fail_rank < 0 .or. fail_rank == rank) &
      call vci_test_malloc_fail_in(int(fail_k, c_long_long), int(fail_min, c_long_long), trim(fail_in)//c_null_char)
#endif
    call vci_ensemble_run_file(factory, cfg, table, trim(path), stat, msg, overwrite=.true., &
                               members_failed=failed)
#ifdef VCI_ENS_MALLOC_FAIL
    if (fail_k > 0 .and. (fail_rank < 0 .or. fail_rank == rank)) then
      if (vci_test_malloc_fail_pending() == 0) then
        print '(a,i0,a,i0,a)', 'rank ', rank, ': allocation ', fail_k, ' failed'
      else
        print '(a,i0,a,i0,a)', 'rank ', rank, ': allocation ', fail_k, ' not reached'
      end if
      call vci_test_malloc_fail(0_c_long_long, 0_c_long_long)
    end if
#endif
    ! a run that stopped (a full disk, a rank's failure) says so: its member count is not a result
    if (rank == 0 .and. stat == VCI_OK) print '(a,i0,a,i0,a)', 'ran ', nm, ' members, ', failed, ' failed'
    if (rank == 0 .and. stat /= VCI_OK) print '(a,i0,a,i0,a)', 'run of ', nm, ' members stopped with status ', stat, &
      ' (the members that failed before it are not counted)'
    if (stat /= VCI_OK) then
      print '(a,i0,a)', 'rank ', rank, ': '//trim(msg)
      flush (6)
#ifdef VCI_HAVE_MPI
      call MPI_Barrier(MPI_COMM_WORLD, ierr)   ! every rank's status printed before any rank ends
#endif
      call finish(1)
    end if
  case ('verify')
    if (rank == 0) call verify(trim(path), partial, with_failures)
  case default
    print '(a)', 'usage: ens_driver run|verify FILE [options]'; call finish(2)
  end select
  call finish(0)

contains

  subroutine verify(file, partial, with_failures)
    character(len=*), intent(in) :: file
    logical, intent(in) :: partial, with_failures
    type(vci_ensemble_results_t) :: got, again
    type(vci_ensemble_table_t) :: tab, sub
    type(vci_ensemble_config_t) :: c
    character(len=:), allocatable :: why
    integer, allocatable :: done(:)
    integer :: j, s, nrun
    call vci_ensemble_read(file, got, s, msg, tab, c)
    if (s /= VCI_OK) then
      print '(a)', 'read failed: '//trim(msg); call finish(1)
    end if
    done = pack([(j, j=1, got%count)], got%status /= VCI_MEMBER_NOT_RUN)
    nrun = size(done)
    print '(a,i0,a,i0,a)', 'file holds ', nrun, ' of ', got%count, ' members'
    if (partial) then
      if (nrun < 1 .or. nrun == got%count) then
        print '(a)', 'FAIL: a killed run should hold some but not all members'; call finish(1)
      end if
    else if (nrun /= got%count) then
      print '(a)', 'FAIL: members missing'; call finish(1)
    end if
    if (with_failures .and. .not. partial) then
      if (got%status(3) /= VCI_ERR_ARGUMENT .or. got%status(5) /= VCI_ERR_INADMISSIBLE .or. &
          got%status(7) /= VCI_ERR_CALLBACK .or. got%status(11) /= VCI_ERR_CALLBACK) then
        print '(a,4i3)', 'FAIL: statuses of the failing members: ', got%status([3, 5, 7, 11]); call finish(1)
      end if
      if (count(got%status /= VCI_OK) /= 4) then
        print '(a)', 'FAIL: members other than 3, 5, 7, 11 failed'; call finish(1)
      end if
      if (any(len_trim(got%message([3, 5, 7, 11])) < 10)) then
        print '(a)', 'FAIL: a failed member without a message'; call finish(1)
      end if
    end if
    ! run the members the file holds again, in memory, and compare
    sub%t0 = tab%t0(done); sub%q0 = tab%q0(:, done); sub%v0 = tab%v0(:, done)
    if (allocated(tab%params)) sub%params = tab%params(:, done)
    c%threads = 1     ! everything else as the file says it was run
    call vci_ensemble_run(factory, c, sub, again, s, msg)
    if (s /= VCI_OK) then
      print '(a)', 'in-memory run failed: '//trim(msg); call finish(1)
    end if
    do j = 1, nrun
      if (.not. results_identical(got, again, why, done(j), j, 1)) then
        print '(a,i0,a)', 'FAIL: member ', done(j), ' differs from its in-memory run in '//why; call finish(1)
      end if
    end do
    print '(a,i0,a)', 'verified: ', nrun, ' members bitwise equal to their in-memory runs'
  end subroutine verify

  integer function int_arg(k)
    integer, intent(in) :: k
    character(len=64) :: v
    call get_command_argument(k, v)
    read (v, *) int_arg
  end function int_arg

  !> End every rank through MPI_Finalize, also after a failure: a run that failed must leave MPI
  !> (and HDF5, whose library closes at exit) as cleanly as one that succeeded; MPI_Abort would hide
  !> an object left open that crashes the finalisation (issue 24, item 5).
  subroutine finish(code)
    integer, intent(in) :: code
#ifdef VCI_HAVE_MPI
    integer :: e
    call MPI_Finalize(e)
#endif
    if (code /= 0) error stop code
    stop
  end subroutine finish
end program ens_driver
