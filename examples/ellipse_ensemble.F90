!> An ensemble of the paper's bouncing ellipse: N perturbations of its start, of sizes from 1e-14 to
!> 1e-2, over T seconds. For each member: when its impact sequence leaves the unperturbed one (the
!> first impact whose time differs from the unperturbed run's by more than --tol, or that one run
!> has and the other has not); over the ensemble: the distribution of impact counts, and the
!> largest Lyapunov exponent from how that divergence time grows as the perturbation shrinks
!> (t_div = ln(tol / size) / lambda + const, fitted over sizes well below tol).
!>
!> Built with MPI, `mpirun -np 2 build/bin/ellipse_ensemble` spreads the members over the ranks and
!> all write one HDF5 file (parallel HDF5); without mpirun, or built without MPI, one process does
!> the same (OpenMP threads either way). The file holds the ensemble (docs/ENSEMBLES.md) and an
!> /analysis group with the numbers printed here; tools/ensemble/plot_ensemble.py draws them.
program ellipse_ensemble
  use, intrinsic :: iso_fortran_env, only: output_unit, error_unit
  use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_is_nan
#ifdef VCI_HAVE_MPI
  use mpi_f08
#endif
  use vci
  use vci_ensemble
#ifdef VCI_HAVE_HDF5
  use hdf5
  use vci_ensemble_h5, only: vci_ensemble_read
  use vci_ensemble_mpi, only: vci_ensemble_run_file
  use vci_hdf5_output, only: vci_hdf5_close_file
#endif
  use vci_scene_ellipse, only: ellipse_model
  use vci_example_cli, only: is_decimal
  implicit none

  real(dp), parameter :: pi = acos(-1.0_dp)
  real(dp), parameter :: q_start(3) = [pi / 2.0_dp, 0.0_dp, 3.5_dp], qdot_start(3) = [-3.0_dp, 2.0_dp, 0.0_dp]
  integer :: n_members = 121, rank = 0, nranks = 1, stat, i, n_failed
  real(dp) :: h = 1.0e-2_dp, t_final = 30.0_dp, min_size = 1.0e-14_dp, max_size = 1.0e-2_dp, tol = 1.0e-2_dp
  integer :: stride = 10, threads = 0, chunk = 0, impact_cap = 256
  ! bounds of the command line's sizes (--help states them); the file's size is checked by the library
  integer, parameter :: members_max = 10000000, impact_cap_max = 1000000, threads_max = 1024
  real(dp), parameter :: h_max = 1.0e6_dp, t_max = 1.0e12_dp, steps_max = 2.0_dp**53
  logical :: quiet = .false., no_output = .false.
  character(len=:), allocatable :: output
  type(vci_prototype_factory_t) :: factory
  type(vci_ensemble_config_t) :: cfg
  type(vci_ensemble_table_t) :: table
  type(vci_ensemble_results_t) :: res
  character(len=VCI_MSG_LEN) :: msg
  real(dp), allocatable :: sizes(:), t_div(:)
  integer, allocatable :: k_div(:)
  real(dp) :: lambda, lambda_err, seconds
  integer :: n_fit
  integer(i8) :: c0, c1, rate
#ifdef VCI_HAVE_MPI
  integer :: provided, ierr
  call MPI_Init_thread(MPI_THREAD_FUNNELED, provided, ierr)
  call MPI_Comm_rank(MPI_COMM_WORLD, rank, ierr)
  call MPI_Comm_size(MPI_COMM_WORLD, nranks, ierr)
#endif
  output = 'ellipse_ensemble.h5'
  call parse_arguments()
#ifndef VCI_HAVE_HDF5
  no_output = .true.      ! built without HDF5: the numbers are printed, no file is written
#endif
#ifndef VCI_HAVE_MPI
  ! started by mpirun but built without MPI: every process would run the whole ensemble into the
  ! same file
  if (launched_by_mpirun()) then
    write (error_unit, '(a)') 'ellipse_ensemble: this build has no MPI, and mpirun started several copies; '// &
      'use the MPI build (cmake --preset mpi && cmake --build --preset mpi: build-mpi/bin/ellipse_ensemble)'
    call finish(2)
  end if
#endif

  ! the table: member 1 unperturbed, member i >= 2 moved by sizes(i) along a fixed direction of its own
  allocate (sizes(n_members), table%t0(n_members), table%q0(3, n_members), table%v0(3, n_members), stat=i)
  if (i /= 0) then
    if (rank == 0) write (error_unit, '(a,i0,a)') 'ellipse_ensemble: no memory for a table of ', n_members, ' members'
    call finish(2)
  end if
  do i = 1, n_members
    sizes(i) = 0.0_dp
    if (i >= 2) sizes(i) = min_size * (max_size / min_size)**(real(i - 2, dp) / real(max(n_members - 2, 1), dp))
    call start_pair(i, sizes(i), table%t0(i), table%q0(:, i), table%v0(:, i))
  end do
  allocate (factory%prototype, source=ellipse_model())
  cfg%h = h
  cfg%nsteps = nint((t_final - (table%t0(1) + h)) / h, i8)   ! bounded by parse_arguments (steps_max)
  cfg%stride = stride; cfg%threads = threads; cfg%chunk = chunk; cfg%impact_cap = impact_cap
  cfg%name = 'ellipse_ensemble: perturbations of the paper''s bouncing ellipse'

  ! wall time of the ensemble itself (with the file: creating, running, writing, closing it)
  call system_clock(c0, rate)
#ifdef VCI_HAVE_HDF5
  if (no_output) then
    if (rank == 0) call vci_ensemble_run(factory, cfg, table, res, stat, msg)
    call system_clock(c1)
  else
    call vci_ensemble_run_file(factory, cfg, table, output, stat, msg, overwrite=.true., members_failed=n_failed)
    call system_clock(c1)
    if (stat == VCI_OK .and. rank == 0) call vci_ensemble_read(output, res, stat, msg)
  end if
#else
  call vci_ensemble_run(factory, cfg, table, res, stat, msg)
  call system_clock(c1)
#endif
  seconds = real(c1 - c0, dp) / real(rate, dp)
  if (stat /= VCI_OK) then
    write (error_unit, '(a,i0,a)') 'ellipse_ensemble (rank ', rank, '): '//trim(msg)
    call finish(1)
  end if

  if (rank == 0) then
    call analyse()
    call report()
#ifdef VCI_HAVE_HDF5
    if (.not. no_output) call write_analysis(output)
#endif
  end if
  call finish(0)

contains

  !> The examples' midpoint pair around the start (q(0), qdot(0)) moved by `size` along member i's
  !> direction: 6 components of a Weyl sequence (fractional parts of i sqrt(p), p prime), normalised.
  subroutine start_pair(i, size, t0, q0, q1)
    integer, intent(in) :: i
    real(dp), intent(in) :: size
    real(dp), intent(out) :: t0, q0(3), q1(3)
    real(dp), parameter :: roots(6) = sqrt([2.0_dp, 3.0_dp, 5.0_dp, 7.0_dp, 11.0_dp, 13.0_dp])
    real(dp) :: u(6), x(3), xd(3)
    u = 2.0_dp * (real(i, dp) * roots - aint(real(i, dp) * roots)) - 1.0_dp
    u = u / norm2(u)
    x = q_start + size * u(1:3)
    xd = qdot_start + size * u(4:6)
    t0 = -0.5_dp * h
    q0 = x - 0.5_dp * h * xd
    q1 = x + 0.5_dp * h * xd
  end subroutine start_pair

  !> Divergence of each member's impact sequence from member 1's, and the Lyapunov fit.
  subroutine analyse()
    integer :: j, k, kmax
    real(dp) :: nan, x(n_members), y(n_members), xm, ym
    nan = ieee_value(1.0_dp, ieee_quiet_nan)
    allocate (t_div(n_members), k_div(n_members))
    t_div = nan; k_div = 0
    do j = 2, n_members
      if (res%status(j) /= VCI_OK) cycle
      kmax = int(min(max(res%impacts(j), res%impacts(1)), int(impact_cap, i8)))
      do k = 1, kmax
        if (k > res%impacts(1) .or. k > res%impacts(j)) then
          ! one run has an impact the other has not: they part at the earlier of the two
          t_div(j) = min(res%impact_t(k, 1), res%impact_t(k, j))
          if (ieee_is_nan(t_div(j))) t_div(j) = max(res%impact_t(k, 1), res%impact_t(k, j))
        else if (abs(res%impact_t(k, j) - res%impact_t(k, 1)) > tol) then
          t_div(j) = min(res%impact_t(k, j), res%impact_t(k, 1))
        end if
        if (.not. ieee_is_nan(t_div(j))) then
          k_div(j) = k; exit
        end if
      end do
    end do
    ! t_div against ln(1/size), over members that parted and whose size is well below tol
    n_fit = 0
    do j = 2, n_members
      if (ieee_is_nan(t_div(j)) .or. sizes(j) > 1.0e-2_dp * tol) cycle
      n_fit = n_fit + 1
      x(n_fit) = log(1.0_dp / sizes(j)); y(n_fit) = t_div(j)
    end do
    lambda = nan; lambda_err = nan
    if (n_fit >= 3) then
      xm = sum(x(1:n_fit)) / n_fit; ym = sum(y(1:n_fit)) / n_fit
      associate (sxx => sum((x(1:n_fit) - xm)**2), sxy => sum((x(1:n_fit) - xm) * (y(1:n_fit) - ym)))
        ! slope s = 1 / lambda; its standard error carried over to lambda
        lambda = sxx / sxy
        lambda_err = lambda**2 * sqrt(sum((y(1:n_fit) - ym - sxy / sxx * (x(1:n_fit) - xm))**2) / &
                                      real(n_fit - 2, dp) / sxx)
      end associate
    end if
  end subroutine analyse

  subroutine report()
    integer :: j, kmin, kmax, k
    integer(i8), allocatable :: counts(:)
    write (output_unit, '(a,i0,a,i0,a,es8.1,a,es8.1,a,f0.2,a,es8.1)') 'ellipse ensemble: ', n_members, &
      ' members on ', nranks, ' rank(s); perturbation sizes ', min_size, ' .. ', max_size, '; T = ', t_final, &
      ' s; h = ', h
    write (output_unit, '(a,i0,a,i0)') 'members failed: ', count(res%status /= VCI_OK), ' of ', n_members
    write (output_unit, '(a,i0,a)') 'unperturbed run: ', res%impacts(1), ' impacts'
    if (.not. quiet) then
      write (output_unit, '(a)') '  member      size  impacts  leaves the unperturbed sequence at'
      do j = 1, n_members
        if (ieee_is_nan(t_div(j))) then
          write (output_unit, '(i8,es10.2,i9,a)') j, sizes(j), res%impacts(j), '  (never within T)'
        else
          write (output_unit, '(i8,es10.2,i9,a,i0,a,f9.4,a)') j, sizes(j), res%impacts(j), '  impact ', &
            k_div(j), ', t = ', t_div(j), ' s'
        end if
      end do
    end if
    kmin = int(minval(res%impacts, res%status == VCI_OK)); kmax = int(maxval(res%impacts, res%status == VCI_OK))
    allocate (counts(kmin:kmax))
    do k = kmin, kmax
      counts(k) = count(res%impacts == k .and. res%status == VCI_OK)
    end do
    write (output_unit, '(a)') 'impact counts (count: members):'
    write (output_unit, '(8(2x,i4,a,i5))') (k, ':', counts(k), k=kmin, kmax)
    write (output_unit, '(a,i0,a,i0)') 'members whose impact sequence left the unperturbed one within T: ', &
      count(.not. ieee_is_nan(t_div)), ' of ', n_members - 1
    if (ieee_is_nan(lambda)) then
      write (output_unit, '(a)') 'largest Lyapunov exponent: too few members parted within T to fit'
    else
      write (output_unit, '(a,f8.4,a,f7.4,a,i0,a,es8.1,a)') 'largest Lyapunov exponent: ', lambda, ' +- ', &
        lambda_err, ' 1/s (fit of the divergence time over ', n_fit, ' members of size <= ', 1.0e-2_dp * tol, ')'
    end if
    write (output_unit, '(a,f8.3,a)') 'wall time: ', seconds, ' s'
    if (.not. no_output) write (output_unit, '(a)') 'file: '//output
  end subroutine report

#ifdef VCI_HAVE_HDF5
  !> /analysis: perturbation size, divergence time and impact index per member; lambda and the
  !> tolerance as attributes (written by one process after the ensemble file is closed). Every
  !> call is checked; after the first failure (a full disk) nothing more is written, and the file
  !> is closed by vci_hdf5_close_file (nothing written at the close: HDF5 crashed at exit with
  !> SIGSEGV) and the program ends with status 1; the file keeps the ensemble.
  subroutine write_analysis(path)
    character(len=*), intent(in) :: path
    integer(hid_t) :: file, g
    integer :: err, e2
    call h5open_f(err)
    file = -1; g = -1
    if (err == 0) call h5fopen_f(path, H5F_ACC_RDWR_F, file, err)
    if (err /= 0) then
      write (error_unit, '(a)') 'ellipse_ensemble: cannot reopen '//path//' for /analysis'; call finish(1)
    end if
    call h5gcreate_f(file, 'analysis', g, err)
    if (err == 0) call put_reals(g, 'size', sizes, err)
    if (err == 0) call put_reals(g, 'divergence_time', t_div, err)
    if (err == 0) call put_ints(g, 'divergence_impact', k_div, err)
    if (err == 0) call put_scalar_real(g, 'lyapunov', lambda, err)
    if (err == 0) call put_scalar_real(g, 'lyapunov_stderr', lambda_err, err)
    if (err == 0) call put_scalar_real(g, 'tolerance', tol, err)
    if (err == 0) call put_scalar_int(g, 'fit_members', n_fit, err)
    if (g >= 0) call h5gclose_f(g, e2)
    call vci_hdf5_close_file(file, e2, failed=err /= 0)
    if (err == 0) err = e2
    if (err /= 0) then
      write (error_unit, '(a)') 'ellipse_ensemble: writing /analysis to '//path//' failed (a full disk?); '// &
        'the file keeps the ensemble'
      call finish(1)
    end if
  end subroutine write_analysis

  subroutine put_reals(g, name, x, err)
    integer(hid_t), intent(in) :: g
    character(len=*), intent(in) :: name
    real(dp), intent(in) :: x(:)
    integer, intent(out) :: err
    integer(hid_t) :: space, dset
    integer :: e2
    dset = -1
    call h5screate_simple_f(1, [int(size(x), hsize_t)], space, err)
    if (err /= 0) return
    call h5dcreate_f(g, name, H5T_IEEE_F64LE, space, dset, err)
    if (err == 0) call h5dwrite_f(dset, H5T_NATIVE_DOUBLE, x, [int(size(x), hsize_t)], err)
    if (dset >= 0) call h5dclose_f(dset, e2)
    call h5sclose_f(space, e2)
  end subroutine put_reals

  subroutine put_ints(g, name, x, err)
    integer(hid_t), intent(in) :: g
    character(len=*), intent(in) :: name
    integer, intent(in) :: x(:)
    integer, intent(out) :: err
    integer(hid_t) :: space, dset
    integer :: e2
    dset = -1
    call h5screate_simple_f(1, [int(size(x), hsize_t)], space, err)
    if (err /= 0) return
    call h5dcreate_f(g, name, H5T_STD_I32LE, space, dset, err)
    if (err == 0) call h5dwrite_f(dset, H5T_NATIVE_INTEGER, x, [int(size(x), hsize_t)], err)
    if (dset >= 0) call h5dclose_f(dset, e2)
    call h5sclose_f(space, e2)
  end subroutine put_ints

  subroutine put_scalar_real(g, name, x, err)
    integer(hid_t), intent(in) :: g
    character(len=*), intent(in) :: name
    real(dp), intent(in) :: x
    integer, intent(out) :: err
    integer(hid_t) :: space, attr
    integer :: e2
    attr = -1
    call h5screate_f(H5S_SCALAR_F, space, err)
    if (err /= 0) return
    call h5acreate_f(g, name, H5T_IEEE_F64LE, space, attr, err)
    if (err == 0) call h5awrite_f(attr, H5T_NATIVE_DOUBLE, x, [1_hsize_t], err)
    if (attr >= 0) call h5aclose_f(attr, e2)
    call h5sclose_f(space, e2)
  end subroutine put_scalar_real

  subroutine put_scalar_int(g, name, x, err)
    integer(hid_t), intent(in) :: g
    character(len=*), intent(in) :: name
    integer, intent(in) :: x
    integer, intent(out) :: err
    integer(hid_t) :: space, attr
    integer :: e2
    attr = -1
    call h5screate_f(H5S_SCALAR_F, space, err)
    if (err /= 0) return
    call h5acreate_f(g, name, H5T_STD_I32LE, space, attr, err)
    if (err == 0) call h5awrite_f(attr, H5T_NATIVE_INTEGER, x, [1_hsize_t], err)
    if (attr >= 0) call h5aclose_f(attr, e2)
    call h5sclose_f(space, e2)
  end subroutine put_scalar_int
#endif

  subroutine parse_arguments()
    integer :: k, n, l
    character(len=512) :: arg
    n = command_argument_count()
    k = 1
    do while (k <= n)
      call get_command_argument(k, arg)
      select case (arg)
      case ('--help', '-h')
        if (rank == 0) then
          write (output_unit, '(a)') 'ellipse_ensemble: perturbations of the paper''s bouncing ellipse'
          write (output_unit, '(a)') '  --members N         members, the first unperturbed, 2 <= N <= 1e7 (121)'
          write (output_unit, '(a)') '  --t-final T         seconds, h < T <= 1e12, at most 2^53 steps of h (30)'
          write (output_unit, '(a)') '  --h H               step length, 0 < H <= 1e6 (1e-2)'
          write (output_unit, '(a)') '  --min-size S, --max-size S   perturbation sizes, log-spaced (1e-14, 1e-2)'
          write (output_unit, '(a)') '  --tol TAU           impact-time difference that counts as leaving (1e-2 s)'
          write (output_unit, '(a)') '  --stride K          keep every K-th state in the file (10; 0: none)'
          write (output_unit, '(a)') '  --impact-cap K      impact times kept per member, 1 <= K <= 1e6 (256)'
          write (output_unit, '(a)') '  --threads T, --chunk C   OpenMP threads (OMP_NUM_THREADS), 0 <= T <= 1024;'
          write (output_unit, '(a)') '                      members per claim, C >= 0 (0: automatic)'
          write (output_unit, '(a)') '  (a file larger than its file system''s free space is refused before it is written)'
          write (output_unit, '(a)') '  --output FILE       the ensemble file (ellipse_ensemble.h5); --no-output'
          write (output_unit, '(a)') '  --quiet             no per-member table'
        end if
        call finish(0)
      case ('--members'); n_members = int_arg(k); k = k + 1
      case ('--t-final'); t_final = real_arg(k); k = k + 1
      case ('--h'); h = real_arg(k); k = k + 1
      case ('--min-size'); min_size = real_arg(k); k = k + 1
      case ('--max-size'); max_size = real_arg(k); k = k + 1
      case ('--tol'); tol = real_arg(k); k = k + 1
      case ('--stride'); stride = int_arg(k); k = k + 1
      case ('--impact-cap'); impact_cap = int_arg(k); k = k + 1
      case ('--threads'); threads = int_arg(k); k = k + 1
      case ('--chunk'); chunk = int_arg(k); k = k + 1
      case ('--output')   ! strict: `--output --quiet` is no file name
        l = 0
        if (k + 1 <= n) call get_command_argument(k + 1, arg, length=l)
        if (k + 1 > n .or. len_trim(arg) == 0 .or. arg(1:2) == '--' .or. trim(arg) == '-h') then
          if (rank == 0) write (error_unit, '(a)') 'ellipse_ensemble: --output needs a value (a file name)'
          call finish(2)
        end if
        if (l > len(arg)) then   ! (was cut to its first 512 characters: another file written)
          if (rank == 0) write (error_unit, '(a,i0,a)') 'ellipse_ensemble: --output: a file name of at most ', &
            len(arg), ' characters'
          call finish(2)
        end if
        output = trim(arg); k = k + 1
      case ('--no-output'); no_output = .true.
      case ('--quiet'); quiet = .true.
      case default
        if (rank == 0) write (error_unit, '(a)') 'ellipse_ensemble: unknown argument '//trim(arg)//' (see --help)'
        call finish(2)
      end select
      k = k + 1
    end do
    if (n_members < 2 .or. n_members > members_max) call refuse('--members must be in [2, 1e7]')
    if (.not. (h > 0.0_dp .and. h <= h_max)) call refuse('--h must be in (0, 1e6]')
    if (.not. (t_final > h .and. t_final <= t_max)) call refuse('--t-final must be in (h, 1e12]')
    if (.not. (min_size > 0.0_dp .and. max_size >= min_size)) call refuse('need 0 < --min-size <= --max-size')
    if (.not. (tol > 0.0_dp)) call refuse('--tol must be positive')
    if (stride < 0) call refuse('--stride must be >= 0')
    if (impact_cap < 1 .or. impact_cap > impact_cap_max) call refuse('--impact-cap must be in [1, 1e6]')
    if (threads < 0 .or. threads > threads_max) call refuse('--threads must be in [0, 1024]')
    if (chunk < 0) call refuse('--chunk must be >= 0')
    ! steps of h from the start pair's second state (t = h / 2) to t-final, before any conversion
    ! to an integer (nint of a larger value wraps)
    if ((t_final - 0.5_dp * h) / h > steps_max) then
      if (rank == 0) write (error_unit, '(a,es10.3,a,es10.3,a)') 'ellipse_ensemble: reaching --t-final ', t_final, &
        ' takes more than 2^53 steps of h = ', h, ' (lower --t-final or raise --h)'
      call finish(2)
    end if
  end subroutine parse_arguments

  subroutine refuse(why)
    character(len=*), intent(in) :: why
    if (rank == 0) write (error_unit, '(a)') 'ellipse_ensemble: '//why
    call finish(2)
  end subroutine refuse

  !> Whether an MPI launcher started this process as one of several (OpenMPI's mpirun, MPICH's).
  logical function launched_by_mpirun()
    character(len=32) :: v
    integer :: k, nproc, ios, st
    character(len=*), parameter :: names(2) = [character(len=21) :: 'OMPI_COMM_WORLD_SIZE', 'PMI_SIZE']
    launched_by_mpirun = .false.
    do k = 1, size(names)
      call get_environment_variable(trim(names(k)), v, status=st)
      if (st /= 0) cycle
      read (v, *, iostat=ios) nproc
      if (ios == 0 .and. nproc > 1) launched_by_mpirun = .true.
    end do
  end function launched_by_mpirun

  !> The value after argument k: one whole decimal number, finite (is_decimal: `1,5` or `inf` are refused).
  real(dp) function real_arg(k)
    integer, intent(in) :: k
    character(len=128) :: v
    integer :: ios, l
    call get_command_argument(k + 1, v, length=l)
    ios = 1
    if (k + 1 <= command_argument_count() .and. l <= len(v)) then
      if (is_decimal(trim(v), integer_only=.false.)) read (v, *, iostat=ios) real_arg
    end if
    if (ios == 0) then
      if (.not. (abs(real_arg) <= huge(real_arg))) ios = 1
    end if
    if (ios /= 0) then
      if (rank == 0) write (error_unit, '(a)') 'ellipse_ensemble: not a finite number after '//trim(arg_name(k))// &
        ': "'//trim(v)//'"'
      call finish(2)
    end if
  end function real_arg

  !> The value after argument k: an integer written with digits only, within the default integer's range.
  integer function int_arg(k)
    integer, intent(in) :: k
    character(len=128) :: v
    integer :: ios, l
    integer(i8) :: big
    call get_command_argument(k + 1, v, length=l)
    ios = 1
    if (k + 1 <= command_argument_count() .and. l <= 18) then
      if (is_decimal(trim(v), integer_only=.true.)) read (v, *, iostat=ios) big
    end if
    if (ios == 0) then
      if (abs(big) > huge(int_arg)) ios = 1
    end if
    if (ios /= 0) then
      if (rank == 0) write (error_unit, '(a)') 'ellipse_ensemble: not an integer after '//trim(arg_name(k))// &
        ': "'//trim(v)//'"'
      call finish(2)
    end if
    int_arg = int(big)
  end function int_arg

  function arg_name(k) result(s)
    integer, intent(in) :: k
    character(len=64) :: s
    call get_command_argument(k, s)
    s = trim(s)
  end function arg_name

  subroutine finish(code)
    integer, intent(in) :: code
#ifdef VCI_HAVE_MPI
    integer :: e
    ! MPI_Abort kills the process without flushing Fortran's buffers: the message written just
    ! before it was lost when stderr is not a terminal
    flush (error_unit); flush (output_unit)
    if (code /= 0 .and. code /= 2) call MPI_Abort(MPI_COMM_WORLD, code, e)
    call MPI_Finalize(e)
#endif
    if (code /= 0) stop code
    stop
  end subroutine finish
end program ellipse_ensemble
