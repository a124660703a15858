!> Ensembles through the C ABI (include/vci.h, "Ensembles"): vci_ensemble_run (OpenMP threads,
!> results into the caller's arrays) and vci_ensemble_run_file (the ensemble HDF5 file, over the
!> ranks of an MPI communicator when the library is built with MPI). Every member is a copy of one
!> model handle's model, discrete or continuous (config->scheme and stages discretise the latter),
!> run by vci_ensemble exactly as the Fortran ensembles run theirs, so a member's result does not
!> depend on the threads, the ranks, or on whether it ran alone.
!> Internal to the bindings: its entry points are public only so that gfortran keeps them.
module vci_capi_ensemble
  use, intrinsic :: iso_c_binding
#ifdef VCI_HAVE_MPI
  use mpi_f08, only: MPI_Comm, MPI_COMM_WORLD
#endif
  use vci_kinds, only: dp, i8
  use vci_status
  use vci_integrator, only: VCI_SCHEME_LEFT, VCI_SCHEME_MIDPOINT, VCI_SCHEME_LOBATTO, VCI_LOBATTO_MAX_STAGES
  use vci_ensemble, only: vci_ensemble_config_t, vci_ensemble_table_t, vci_ensemble_results_t, &
                          vci_model_factory_t, vci_prototype_factory_t, vci_lagrangian_prototype_factory_t, &
                          vci_ensemble_run, vci_ensemble_check
#ifdef VCI_HAVE_HDF5
  use vci_ensemble_mpi, only: vci_ensemble_run_file
#endif
  use vci_capi_models, only: c_model_t, c_lagrangian_t
  use vci_capi_registry, only: lock_registry, unlock_registry, find_live, slots, KIND_MODEL, set_thread_message
  implicit none
  private

  public :: vci_ensemble_run_c, vci_ensemble_run_file_c
  public :: vci_ensemble_config_c, vci_ensemble_results_c

  !> Mirror of `struct vci_ensemble_config` (vci.h): a leading size, then members of 8 bytes each,
  !> added at the end only. Defaults are those of VCI_ENSEMBLE_CONFIG_INIT; members beyond a
  !> caller's size keep them.
  type, bind(C) :: vci_ensemble_config_c
    integer(c_size_t) :: size = 0
    real(c_double) :: h = 0.0_c_double
    integer(c_int64_t) :: nsteps = 0, direction = 1, start_kind = 0, scheme = -1, stages = 0
    real(c_double) :: atol = -1.0_c_double, rtol = -1.0_c_double
    integer(c_int64_t) :: max_iterations = 0, impact_energy = -1, max_impacts_per_step = 0
    integer(c_int64_t) :: impact_cap = 0, stride = 0, threads = 0, chunk = 0
  end type vci_ensemble_config_c

  !> Mirror of `struct vci_ensemble_results` (vci.h): a leading size, then the caller's output
  !> arrays (NULL: not wanted) and the length of each member's message slot.
  type, bind(C) :: vci_ensemble_results_c
    integer(c_size_t) :: size = 0
    type(c_ptr) :: status = c_null_ptr, t = c_null_ptr, q = c_null_ptr, p = c_null_ptr
    type(c_ptr) :: steps = c_null_ptr, impacts = c_null_ptr, newton_iterations = c_null_ptr
    type(c_ptr) :: energy_start = c_null_ptr, energy_end = c_null_ptr
    type(c_ptr) :: impact_t = c_null_ptr, impact_gap = c_null_ptr, messages = c_null_ptr
    integer(c_int64_t) :: message_size = 0
  end type vci_ensemble_results_c

  integer, parameter :: WORD = 8   ! bytes of every member of the two structs

contains

  !> int vci_ensemble_run(vci_model model, const vci_ensemble_config *config, int64_t members,
  !> const double *t0, const double *q0, const double *v0, const vci_ensemble_results *results)
  integer(c_int) function vci_ensemble_run_c(model, config, members, t0, q0, v0, results) &
    bind(C, name='vci_ensemble_run')
    type(c_ptr), value :: model, config, t0, q0, v0, results
    integer(c_int64_t), value :: members
    character(len=*), parameter :: who = 'vci_ensemble_run'
    class(vci_model_factory_t), allocatable :: factory
    type(vci_ensemble_config_t) :: cfg
    type(vci_ensemble_table_t) :: table
    type(vci_ensemble_results_t) :: res
    type(vci_ensemble_results_c) :: out
    character(len=VCI_MSG_LEN) :: msg
    integer :: stat
    vci_ensemble_run_c = VCI_ERR_ARGUMENT
    if (.not. c_associated(results)) then
      call set_thread_message(who//': the results argument is NULL'); return
    end if
    if (.not. read_results(who, results, out)) return
    stat = prepare(who, model, config, members, t0, q0, v0, factory, cfg, table)
    if (stat /= VCI_OK) then
      vci_ensemble_run_c = stat; return
    end if
    call vci_ensemble_run(factory, cfg, table, res, stat, msg)
    if (stat /= VCI_OK) then
      call set_thread_message(who//': '//trim(msg))
      vci_ensemble_run_c = stat; return
    end if
    call write_results(res, out, int(members), int(cfg%impact_cap))
    call set_thread_message('')
    vci_ensemble_run_c = VCI_OK
  end function vci_ensemble_run_c

  !> int vci_ensemble_run_file(vci_model model, const vci_ensemble_config *config, int64_t members,
  !> const double *t0, const double *q0, const double *v0, const char *path, int overwrite,
  !> int mpi_comm, int64_t *members_failed)
  integer(c_int) function vci_ensemble_run_file_c(model, config, members, t0, q0, v0, path, overwrite, &
                                                  comm_handle, members_failed) bind(C, name='vci_ensemble_run_file')
    type(c_ptr), value :: model, config, t0, q0, v0, path, members_failed
    integer(c_int64_t), value :: members
    integer(c_int), value :: overwrite, comm_handle
    character(len=*), parameter :: who = 'vci_ensemble_run_file'
    character(len=:), allocatable :: fpath
    integer(c_int64_t), pointer :: nfailed
    integer :: failed
    vci_ensemble_run_file_c = VCI_ERR_ARGUMENT
    if (c_associated(members_failed)) then
      call c_f_pointer(members_failed, nfailed)
      nfailed = 0
    end if
    if (.not. c_string(path, fpath)) then
      call set_thread_message(who//': the path is NULL or empty'); return
    end if
#ifdef VCI_HAVE_HDF5
    failed = 0
    vci_ensemble_run_file_c = run_file(who, model, config, members, t0, q0, v0, fpath, overwrite /= 0, &
                                       comm_handle, failed)
    if (c_associated(members_failed)) nfailed = failed
#else
    call set_thread_message(who//': this library was built without HDF5 (VCI_WITH_HDF5=OFF)')
    vci_ensemble_run_file_c = VCI_ERR_IO
#endif
  end function vci_ensemble_run_file_c

#ifdef VCI_HAVE_HDF5
  !> vci_ensemble_run_file's run once its pointers are checked: prepare, then the file driver
  !> (collective over the communicator with MPI). The status, `failed` = members that failed.
  integer function run_file(who, model, config, members, t0, q0, v0, fpath, overwrite, comm_handle, failed) &
    result(stat)
    character(len=*), intent(in) :: who, fpath
    type(c_ptr), intent(in) :: model, config, t0, q0, v0
    integer(c_int64_t), intent(in) :: members
    logical, intent(in) :: overwrite
    integer(c_int), intent(in) :: comm_handle
    integer, intent(out) :: failed
    class(vci_model_factory_t), allocatable :: factory
    type(vci_ensemble_config_t) :: cfg
    type(vci_ensemble_table_t) :: table
    character(len=VCI_MSG_LEN) :: msg
#ifdef VCI_HAVE_MPI
    type(MPI_Comm) :: comm
#endif
    failed = 0
    stat = prepare(who, model, config, members, t0, q0, v0, factory, cfg, table)
    if (stat /= VCI_OK) return
#ifdef VCI_HAVE_MPI
    ! -1: MPI_COMM_WORLD; else a Fortran handle (MPI_Comm_c2f)
    comm = MPI_COMM_WORLD
    if (comm_handle /= -1) comm%MPI_VAL = int(comm_handle)
    call vci_ensemble_run_file(factory, cfg, table, fpath, stat, msg, overwrite, failed, comm)
#else
    ! one process: the communicator is not looked at
    call vci_ensemble_run_file(factory, cfg, table, fpath, stat, msg, overwrite, failed)
#endif
    if (stat /= VCI_OK) then
      call set_thread_message(who//': '//trim(msg))
    else
      call set_thread_message('')
    end if
  end function run_file
#endif

  !> The two entries' common part: the configuration, the members' starts and the factory of the
  !> model handle's model. VCI_OK, or a status with the thread's message saying why.
  integer function prepare(who, model, config, members, t0, q0, v0, factory, cfg, table) result(stat)
    character(len=*), intent(in) :: who
    type(c_ptr), intent(in) :: model, config, t0, q0, v0
    integer(c_int64_t), intent(in) :: members
    class(vci_model_factory_t), allocatable, intent(out) :: factory
    type(vci_ensemble_config_t), intent(out) :: cfg
    type(vci_ensemble_table_t), intent(out) :: table
    type(c_model_t) :: mcopy
    type(vci_ensemble_config_c) :: c
    real(c_double), pointer :: a(:), a2(:, :)
    character(len=VCI_MSG_LEN) :: msg
    integer :: i, n, s
    stat = VCI_ERR_ARGUMENT
    if (.not. read_config(who, config, c)) return
    call lock_registry()
    i = find_live(model, KIND_MODEL)
    if (i > 0) mcopy = slots(i)%model
    call unlock_registry()
    if (i == 0) then
      if (.not. c_associated(model)) then
        call set_thread_message(who//': the model handle is NULL')
      else
        call set_thread_message(who//': not a live model handle (destroyed, or not made by vci_model_create '// &
                                'or vci_model_create_lagrangian)')
      end if
      return
    end if
    call mcopy%record%clear()
    if (mcopy%separable) then
      ! the ensemble driver builds its members from the continuous or discrete callbacks only
      call set_thread_message(who//': a separable model (vci_model_create_separable) cannot run in an '// &
        'ensemble yet; create the same L with vci_model_create_lagrangian')
      return
    end if
    if (members < 1 .or. members > int(huge(1) / max(mcopy%n, 1), c_int64_t)) then
      write (msg, '(a,i0,a)') who//': members = ', members, ' (need 1 <= members, and members * n < 2^31)'
      call set_thread_message(msg); return
    end if
    if (.not. (c_associated(t0) .and. c_associated(q0) .and. c_associated(v0))) then
      call set_thread_message(who//': t0, q0 or v0 is NULL'); return
    end if
    if (mcopy%continuous) then
      if (c%scheme /= -1 .and. c%scheme /= VCI_SCHEME_LEFT .and. c%scheme /= VCI_SCHEME_MIDPOINT .and. &
          c%scheme /= VCI_SCHEME_LOBATTO) then
        write (msg, '(a,i0,a)') who//': config->scheme = ', c%scheme, ' (a C model takes VCI_SCHEME_LEFT, '// &
          '_MIDPOINT or _LOBATTO, or -1 for the default, midpoint)'
        call set_thread_message(msg); return
      end if
      if (c%scheme == VCI_SCHEME_LOBATTO .and. (c%stages < 1 .or. c%stages > VCI_LOBATTO_MAX_STAGES)) then
        write (msg, '(a,i0,a,i0,a)') who//': config->stages = ', c%stages, ' for lobatto (need 1..', &
          VCI_LOBATTO_MAX_STAGES, ')'
        call set_thread_message(msg); return
      end if
    else if (c%scheme /= -1) then
      write (msg, '(a,i0,a)') who//': config->scheme = ', c%scheme, ' for a discrete model (it is its own '// &
        'scheme: leave -1)'
      call set_thread_message(msg); return
    end if
    if (c%impact_energy /= -1 .and. c%impact_energy /= 0 .and. c%impact_energy /= 1) then
      write (msg, '(a,i0,a)') who//': config->impact_energy = ', c%impact_energy, &
        ' (VCI_IMPACT_DISCRETE, VCI_IMPACT_HAMILTONIAN or -1)'
      call set_thread_message(msg); return
    end if
    if (any([c%direction, c%start_kind, c%scheme, c%stages, c%max_iterations, c%impact_energy, &
             c%max_impacts_per_step, c%impact_cap, c%threads, c%chunk] > int(huge(1), c_int64_t)) .or. &
        any([c%direction, c%start_kind, c%stages, c%max_iterations, c%max_impacts_per_step, c%impact_cap, &
             c%threads, c%chunk] < -int(huge(1), c_int64_t))) then
      call set_thread_message(who//': a setting of config is beyond the range of int'); return
    end if
    cfg%h = c%h; cfg%nsteps = c%nsteps; cfg%direction = int(c%direction); cfg%start_kind = int(c%start_kind)
    cfg%atol = c%atol; cfg%rtol = c%rtol; cfg%max_iterations = int(c%max_iterations)
    cfg%impact_energy = int(c%impact_energy); cfg%max_impacts_per_step = int(c%max_impacts_per_step)
    cfg%scheme = int(c%scheme); cfg%stages = int(c%stages)
    cfg%impact_cap = int(c%impact_cap); cfg%stride = c%stride; cfg%threads = int(c%threads)
    cfg%chunk = int(c%chunk)
    cfg%name = 'C ensemble'
    if (c%atol >= 0.0_dp .and. c%rtol >= 0.0_dp .and. c%atol == 0.0_dp .and. c%rtol == 0.0_dp) then
      call set_thread_message(who//': config->atol and config->rtol are both 0'); return
    end if

    n = mcopy%n
    allocate (table%t0(members), table%q0(n, members), table%v0(n, members), stat=s)
    if (s /= 0) then
      call set_thread_message(who//': out of memory for the members'' starts')
      stat = VCI_ERR_MEMORY; return
    end if
    call c_f_pointer(t0, a, [members]); table%t0 = a
    ! (through rank-2 pointers: a reshape would be a temporary of n * members allocated without stat=)
    call c_f_pointer(q0, a2, [n, int(members)]); table%q0 = a2
    call c_f_pointer(v0, a2, [n, int(members)]); table%v0 = a2
    call vci_ensemble_check(cfg, table, s, msg)
    if (s /= VCI_OK) then
      call set_thread_message(who//': '//trim(msg))
      stat = s; return
    end if

    if (mcopy%continuous) then
      block
        type(vci_lagrangian_prototype_factory_t), allocatable :: lf
        type(c_lagrangian_t), allocatable :: lag
        allocate (lf, lag, stat=s)
        if (s == 0) then
          ! each member's copy keeps its callbacks' failures in its own record (record => null)
          lag%n = mcopy%n; lag%m = mcopy%m; lag%n_gaps = mcopy%n_gaps
          lag%cb = mcopy%lcb; lag%user = mcopy%user
          call move_alloc(lag, lf%prototype)
          call move_alloc(lf, factory)
        end if
      end block
    else
      block
        type(vci_prototype_factory_t), allocatable :: df
        allocate (df, stat=s)
        if (s == 0) allocate (df%prototype, source=mcopy, stat=s)
        if (s == 0) call move_alloc(df, factory)
      end block
    end if
    if (s /= 0) then
      call set_thread_message(who//': out of memory for the model')
      stat = VCI_ERR_MEMORY; return
    end if
    stat = VCI_OK
  end function prepare

  !> The caller's vci_ensemble_config at p into c (defaults beyond its size); false with the
  !> thread's message when it is NULL, its size is no header's, or it sets members this library
  !> does not know.
  logical function read_config(who, p, c) result(ok)
    character(len=*), intent(in) :: who
    type(c_ptr), intent(in) :: p
    type(vci_ensemble_config_c), intent(out) :: c
    integer(c_int64_t) :: words(c_sizeof(c) / WORD)
    integer(c_int64_t), pointer :: src(:)
    integer :: k
    ok = .false.
    if (.not. c_associated(p)) then
      call set_thread_message(who//': the config argument is NULL'); return
    end if
    ! required: size, h, nsteps
    if (.not. whole(who, 'config', 'vci_ensemble_config', 'VCI_ENSEMBLE_CONFIG_INIT', p, c_sizeof(c), 3 * WORD, &
                    k)) return
    c = vci_ensemble_config_c()
    words = transfer(c, words)
    call c_f_pointer(p, src, [k])
    words(2:min(k, size(words))) = src(2:min(k, size(words)))
    c = transfer(words, c)
    c%size = c_sizeof(c)
    ok = .true.
  end function read_config

  !> The caller's vci_ensemble_results at p (NULL beyond its size), as read_config.
  logical function read_results(who, p, r) result(ok)
    character(len=*), intent(in) :: who
    type(c_ptr), intent(in) :: p
    type(vci_ensemble_results_c), intent(out) :: r
    integer(c_int64_t) :: words(c_sizeof(r) / WORD)
    integer(c_int64_t), pointer :: src(:)
    integer :: k
    ok = .false.
    if (.not. whole(who, 'results', 'vci_ensemble_results', 'VCI_ENSEMBLE_RESULTS_INIT', p, c_sizeof(r), WORD, k)) &
      return
    r = vci_ensemble_results_c()
    words = transfer(r, words)
    call c_f_pointer(p, src, [k])
    words(2:min(k, size(words))) = src(2:min(k, size(words)))
    r = transfer(words, r)
    r%size = c_sizeof(r)
    if (c_associated(r%messages) .and. r%message_size < 1) then
      call set_thread_message(who//': results->messages is given with message_size < 1'); ok = .false.; return
    end if
    ok = .true.
  end function read_results

  !> A versioned struct at p (size field first, members of 8 bytes): its size must be a whole number
  !> of members, at least `least` bytes, at most 4096; members beyond `ours` bytes (a newer header's)
  !> must be 0. k = its number of 8-byte words.
  logical function whole(who, arg, struct, init, p, ours, least, k) result(ok)
    character(len=*), intent(in) :: who, arg, struct, init
    type(c_ptr), intent(in) :: p
    integer(c_size_t), intent(in) :: ours
    integer, intent(in) :: least
    integer, intent(out) :: k
    integer(c_size_t), pointer :: nbytes
    integer(c_int64_t), pointer :: src(:)
    character(len=24) :: txt
    ok = .false.
    k = 0
    call c_f_pointer(p, nbytes)
    if (nbytes < least .or. nbytes > 4096 .or. mod(nbytes, int(WORD, c_size_t)) /= 0) then
      write (txt, '(i0)') nbytes
      if (nbytes < 0) txt = 'beyond 2^63'
      call set_thread_message(who//': '//arg//'->size = '//trim(txt)//' is not the size of a '//struct// &
                              ' (initialise it with '//init//')')
      return
    end if
    k = int(nbytes / WORD)
    if (nbytes > ours) then
      call c_f_pointer(p, src, [k])
      if (any(src(ours / WORD + 1:k) /= 0)) then
        call set_thread_message(who//': '//arg//' sets members this library does not know (the program '// &
                                'was built against a newer vci.h)')
        return
      end if
    end if
    ok = .true.
  end function whole

  !> The Fortran results into the caller's arrays (those not NULL); gap indices from 0, -1 for none.
  !> The tables go through rank-2 pointers of the caller's arrays, element by element: a reshape
  !> (or `values - 1`) would be a temporary of the table's size allocated without stat=, whose
  !> failure is a runtime error that ends the caller's program.
  subroutine write_results(res, out, members, cap)
    type(vci_ensemble_results_t), intent(in) :: res
    type(vci_ensemble_results_c), intent(in) :: out
    integer, intent(in) :: members, cap
    character(kind=c_char), pointer :: txt(:)
    integer :: j, l, len_msg
    call put_i32(out%status, res%status)
    call put_f64(out%t, res%t)
    call put_f64_table(out%q, res%q)
    call put_f64_table(out%p, res%p)
    call put_i64(out%steps, res%steps)
    call put_i64(out%impacts, res%impacts)
    call put_i64(out%newton_iterations, res%newton_iterations)
    call put_f64(out%energy_start, res%energy_start)
    call put_f64(out%energy_end, res%energy_end)
    if (cap > 0) then
      call put_f64_table(out%impact_t, res%impact_t)
      call put_gap_table(out%impact_gap, res%impact_gap)
    end if
    if (c_associated(out%messages)) then
      len_msg = int(min(out%message_size, int(huge(1) / members, c_int64_t)))
      call c_f_pointer(out%messages, txt, [len_msg * members])
      do j = 1, members
        l = min(len_trim(res%message(j)), len_msg - 1)
        txt((j - 1) * len_msg + 1:(j - 1) * len_msg + l) = transfer(res%message(j)(1:l), txt, l)
        txt((j - 1) * len_msg + l + 1) = c_null_char
      end do
    end if
  end subroutine write_results

  !> values into the caller's double array at p (nothing when p is NULL).
  subroutine put_f64(p, values)
    type(c_ptr), intent(in) :: p
    real(dp), intent(in) :: values(:)
    real(c_double), pointer :: d(:)
    if (.not. c_associated(p)) return
    call c_f_pointer(p, d, [size(values)])
    d = values
  end subroutine put_f64

  !> The table values into the caller's double array at p, column by column (nothing when p is NULL).
  subroutine put_f64_table(p, values)
    type(c_ptr), intent(in) :: p
    real(dp), intent(in) :: values(:, :)
    real(c_double), pointer :: d(:, :)
    integer :: j
    if (.not. c_associated(p)) return
    call c_f_pointer(p, d, shape(values))
    do j = 1, size(values, 2)
      d(:, j) = values(:, j)
    end do
  end subroutine put_f64_table

  !> The gap indices (from 1, 0 for none) into the caller's int array at p, from 0 (-1 for none).
  subroutine put_gap_table(p, gaps)
    type(c_ptr), intent(in) :: p
    integer, intent(in) :: gaps(:, :)
    integer(c_int), pointer :: d(:, :)
    integer :: i, j
    if (.not. c_associated(p)) return
    call c_f_pointer(p, d, shape(gaps))
    do j = 1, size(gaps, 2)
      do i = 1, size(gaps, 1)
        d(i, j) = gaps(i, j) - 1
      end do
    end do
  end subroutine put_gap_table

  !> values into the caller's int array at p (nothing when p is NULL).
  subroutine put_i32(p, values)
    type(c_ptr), intent(in) :: p
    integer, intent(in) :: values(:)
    integer(c_int), pointer :: d(:)
    if (.not. c_associated(p)) return
    call c_f_pointer(p, d, [size(values)])
    d = values
  end subroutine put_i32

  !> values into the caller's int64_t array at p (nothing when p is NULL).
  subroutine put_i64(p, values)
    type(c_ptr), intent(in) :: p
    integer(i8), intent(in) :: values(:)
    integer(c_int64_t), pointer :: d(:)
    if (.not. c_associated(p)) return
    call c_f_pointer(p, d, [size(values)])
    d = values
  end subroutine put_i64

  !> The NUL-terminated string at p as a Fortran string; false when p is NULL or the string empty.
  logical function c_string(p, s) result(ok)
    type(c_ptr), intent(in) :: p
    character(len=:), allocatable, intent(out) :: s
    character(kind=c_char), pointer :: c(:)
    integer :: l
    interface
      integer(c_size_t) function strlen(str) bind(C, name='strlen')
        import :: c_size_t, c_ptr
        type(c_ptr), value :: str
      end function strlen
    end interface
    ok = .false.
    if (.not. c_associated(p)) return
    l = int(min(strlen(p), 4096_c_size_t))
    if (l == 0) return
    call c_f_pointer(p, c, [l])
    allocate (character(len=l) :: s)   ! (at most 4096 characters: tiny, no stat=)
    s = transfer(c, s(1:l))
    ok = .true.
  end function c_string
end module vci_capi_ensemble
