!> The C ABI of vci (include/vci.h): its exported functions, each a thin shell that checks its
!> arguments, enters the call on a handle (vci_capi_registry), calls the Fortran API and reports a
!> status. The handles and the objects behind them are in vci_capi_registry, the C models in
!> vci_capi_models; these three modules are the only ones that speak iso_c_binding for C callers.
module vci_capi
  use, intrinsic :: iso_c_binding
  use vci_kinds, only: dp, i8
  use vci_status
  use vci_limits, only: vci_size_problem
  use vci_integrator, only: vci_stats_t
  use vci, only: VCI_VERSION_NUMBER, sparse_available_f => vci_sparse_available
  use vci_model_check, only: vci_check_model, vci_check_report_t
#ifdef VCI_HAVE_HDF5
  use vci_hdf5_output, only: vci_hdf5_writer_t, vci_hdf5_read_checkpoint
  use vci_checkpoint, only: vci_checkpoint_t
#endif
  use vci_sparse, only: pattern_arrays_error
  use vci_capi_models
  use vci_capi_registry
  implicit none
  private

  public :: vci_model_create_v2, vci_model_create_v0_1, vci_model_create_lagrangian, vci_model_destroy
  public :: vci_set_scheme
  public :: vci_model_create_separable
  public :: vci_integrator_create, vci_integrator_destroy
  public :: vci_set_tolerances, vci_set_impact_energy, vci_set_max_impacts
  public :: vci_init_from_pair, vci_init_from_momentum, vci_step, vci_integrate
  public :: vci_get_state, vci_get_multipliers, vci_get_energy, vci_get_index, vci_get_stats
  public :: vci_get_energy_fallbacks
  public :: vci_get_irreversible_impacts
  public :: vci_set_step_splits, vci_get_split_steps
  public :: vci_set_poke_samples
  public :: vci_set_bordered_impacts, vci_get_bordered_directions
  public :: vci_set_impact_callback, vci_open_output, vci_open_output_every, vci_close_output
  public :: vci_append_output, vci_restore_from_file
  public :: vci_last_error, vci_status_string, vci_version
  public :: vci_model_declare_pattern, vci_sparse_available

  !> mass_kind of vci_model_create_separable (vci.h: VCI_MASS_DIAGONAL, VCI_MASS_DENSE)
  integer, parameter :: VCI_MASS_DIAGONAL_C = 0, VCI_MASS_DENSE_C = 1

  ! NUL-terminated status strings handed out by vci_status_string: initialised at load time, read-only
  integer, parameter :: STATUS_LEN = 40
  integer, parameter :: N_STATUS = ubound(VCI_STATUS_NAMES, 1)
  integer :: i_
  character(kind=c_char, len=STATUS_LEN), target, save :: status_text(0:N_STATUS + 1) = &
    [character(kind=c_char, len=STATUS_LEN) :: (trim(VCI_STATUS_NAMES(i_))//c_null_char, i_ = 0, N_STATUS), &
     'unknown status'//c_null_char]

contains

  ! ---------------------------------------------------------------------------------------------
  ! the C entry points (vci.h documents each one's statuses)

  !> int vci_model_create_v2(vci_model *model, int n, int m, int ngaps, const vci_callbacks *cb,
  !> void *user): vci.h's vci_model_create. Reads cb->size bytes of the callbacks.
  integer(c_int) function vci_model_create_v2(model, n, m, ngaps, cb, user) bind(C, name='vci_model_create_v2')
    type(c_ptr), value :: model, cb, user
    integer(c_int), value :: n, m, ngaps
    type(vci_callbacks_c), target :: local
    integer(c_int8_t), pointer :: src(:), dst(:)
    integer(c_size_t) :: nbytes, ours
    integer :: k
    vci_model_create_v2 = VCI_ERR_ARGUMENT
    ours = c_sizeof(local)
    ! up to d3_ld: the required ones
    if (.not. callbacks_usable('vci_model_create', model, cb, ours, c_sizeof(local%size) + 3 * c_sizeof(c_null_funptr), &
                               'vci_callbacks', 'VCI_CALLBACKS_INIT', nbytes)) return
    call c_f_pointer(cb, src, [nbytes])
    local = vci_callbacks_c()
    call c_f_pointer(c_loc(local), dst, [ours])
    k = int(min(nbytes, ours))
    dst(1:k) = src(1:k)
    local%size = ours
    vci_model_create_v2 = create_model('vci_model_create', model, n, m, ngaps, local, user)
  end function vci_model_create_v2

  !> int vci_model_create(...) as vci.h 0.1.0 declared it: the callbacks are nine pointers with no
  !> size field. Kept (under its 0.1 symbol name) for binaries built against 0.1.
  integer(c_int) function vci_model_create_v0_1(model, n, m, ngaps, cb, user) bind(C, name='vci_model_create')
    type(c_ptr), value :: model, cb, user
    integer(c_int), value :: n, m, ngaps
    type(vci_callbacks_v0_1), pointer :: old
    type(vci_callbacks_c) :: local
    vci_model_create_v0_1 = VCI_ERR_ARGUMENT
    if (.not. pointers_given('vci_model_create', model, cb)) return
    call c_f_pointer(cb, old)
    local = vci_callbacks_c(c_sizeof(local), old%d1_ld, old%d2_ld, old%d3_ld, old%mixed_hessian, &
                            old%constraint_forms, old%discrete_constraint, old%gaps, old%gap_gradients, old%energy)
    vci_model_create_v0_1 = create_model('vci_model_create', model, n, m, ngaps, local, user)
  end function vci_model_create_v0_1

  !> int vci_model_create_lagrangian(vci_model *model, int n, int m, int ngaps,
  !> const vci_lagrangian_callbacks *cb, void *user). Reads cb->size bytes of the callbacks (the
  !> rules of vci_model_create_v2).
  integer(c_int) function vci_model_create_lagrangian(model, n, m, ngaps, cb, user) &
    bind(C, name='vci_model_create_lagrangian')
    type(c_ptr), value :: model, cb, user
    integer(c_int), value :: n, m, ngaps
    type(vci_lagrangian_callbacks_c) :: local
    type(c_funptr), pointer :: fps(:)
    integer(c_size_t) :: nbytes, ours
    character(len=64) :: what
    integer :: k, i
    vci_model_create_lagrangian = VCI_ERR_ARGUMENT
    ours = c_sizeof(local)
    ! up to dl_dv: the required ones
    if (.not. callbacks_usable('vci_model_create_lagrangian', model, cb, ours, &
                               c_sizeof(local%size) + 3 * c_sizeof(c_null_funptr), 'vci_lagrangian_callbacks', &
                               'VCI_LAGRANGIAN_CALLBACKS_INIT', nbytes)) return
    ! the members the caller's header has (those beyond its size stay NULL), one by one: a byte copy
    ! into `local` through a second pointer was lost to gfortran's optimiser
    k = int((min(nbytes, ours) - c_sizeof(local%size)) / c_sizeof(c_null_funptr))
    call c_f_pointer(transfer(transfer(cb, 0_c_intptr_t) + c_sizeof(local%size), cb), fps, [k])
    local = vci_lagrangian_callbacks_c()
    local%size = ours
    do i = 1, k
      select case (i)
      case (1); local%lagrangian = fps(i)
      case (2); local%dl_dq = fps(i)
      case (3); local%dl_dv = fps(i)
      case (4); local%hessians = fps(i)
      case (5); local%constraint_forms = fps(i)
      case (6); local%gaps = fps(i)
      case (7); local%gap_gradients = fps(i)
      case (8); local%energy = fps(i)
      case (9); local%hessians_band = fps(i)
      case (10); local%hessians_sparse = fps(i)
      end select
    end do
    what = ''
    if (.not. c_associated(local%lagrangian)) what = 'lagrangian'
    if (.not. c_associated(local%dl_dq)) what = 'dl_dq'
    if (.not. c_associated(local%dl_dv)) what = 'dl_dv'
    if (m > 0 .and. .not. c_associated(local%constraint_forms)) what = 'constraint_forms (needed as m > 0)'
    if (ngaps > 0 .and. .not. c_associated(local%gaps)) what = 'gaps (needed as ngaps > 0)'
    if (what /= '') then
      call set_thread_message('vci_model_create_lagrangian: callback '//trim(what)//' is NULL (lagrangian, '// &
                              'dl_dq and dl_dv are required)')
      return
    end if
    ! sizes, allocation and registry as for a discrete model
    vci_model_create_lagrangian = create_model('vci_model_create_lagrangian', model, n, m, ngaps, vci_callbacks_c(), user, local)
  end function vci_model_create_lagrangian

  !> int vci_model_create_separable(vci_model *model, int n, int m, int ngaps, int mass_kind,
  !> const double *mass, const vci_separable_callbacks *cb, void *user): L = ½ q̇ᵀ M q̇ − V(q)
  !> with a constant M (mass_kind 0: diagonal, mass[n]; 1: dense, mass[n*n] column-major).
  !> Reads cb->size bytes of the callbacks (the rules of vci_model_create_v2). m must be 0:
  !> constraints are not part of this kind (the explicit schemes cannot impose them).
  integer(c_int) function vci_model_create_separable(model, n, m, ngaps, mass_kind, mass, cb, user) &
    bind(C, name='vci_model_create_separable')
    type(c_ptr), value :: model, mass, cb, user
    integer(c_int), value :: n, m, ngaps, mass_kind
    type(vci_separable_callbacks_c) :: local
    type(c_funptr), pointer :: fps(:)
    real(c_double), pointer :: mf(:)
    type(c_separable_t) :: probe
    type(c_model_t), target :: trial
    integer(c_size_t) :: nbytes, ours
    character(len=64) :: what
    character(len=VCI_MSG_LEN) :: msg
    integer :: k, i, nm, st
    vci_model_create_separable = VCI_ERR_ARGUMENT
    ours = c_sizeof(local)
    ! up to potential_gradient: the required ones
    if (.not. callbacks_usable('vci_model_create_separable', model, cb, ours, &
                               c_sizeof(local%size) + 2 * c_sizeof(c_null_funptr), 'vci_separable_callbacks', &
                               'VCI_SEPARABLE_CALLBACKS_INIT', nbytes)) return
    k = int((min(nbytes, ours) - c_sizeof(local%size)) / c_sizeof(c_null_funptr))
    call c_f_pointer(transfer(transfer(cb, 0_c_intptr_t) + c_sizeof(local%size), cb), fps, [k])
    local = vci_separable_callbacks_c()
    local%size = ours
    do i = 1, k          ! one by one, as vci_model_create_lagrangian (no byte copy)
      select case (i)
      case (1); local%potential = fps(i)
      case (2); local%potential_gradient = fps(i)
      case (3); local%potential_hessian = fps(i)
      case (4); local%gaps = fps(i)
      case (5); local%gap_gradients = fps(i)
      end select
    end do
    if (m /= 0) then
      write (msg, '(a,i0,a)') 'vci_model_create_separable: m = ', m, ' but a separable model has no '// &
        'nonholonomic constraints (the explicit schemes cannot impose them): give the model with '// &
        'vci_model_create_lagrangian and use lobatto (order 2s with constraints) or midpoint'
      call set_thread_message(msg); return
    end if
    what = ''
    if (.not. c_associated(local%potential)) what = 'potential'
    if (.not. c_associated(local%potential_gradient)) what = 'potential_gradient'
    if (ngaps > 0 .and. .not. c_associated(local%gaps)) what = 'gaps (needed as ngaps > 0)'
    if (ngaps > 0 .and. .not. c_associated(local%gap_gradients)) what = 'gap_gradients (needed as ngaps > 0)'
    if (what /= '') then
      call set_thread_message('vci_model_create_separable: callback '//trim(what)//' is NULL (potential and '// &
                              'potential_gradient are required; gaps and gap_gradients when ngaps > 0)')
      return
    end if
    if (mass_kind /= VCI_MASS_DIAGONAL_C .and. mass_kind /= VCI_MASS_DENSE_C) then
      write (msg, '(a,i0,a)') 'vci_model_create_separable: mass_kind = ', mass_kind, &
        ' (need VCI_MASS_DIAGONAL = 0 or VCI_MASS_DENSE = 1)'
      call set_thread_message(msg); return
    end if
    if (.not. c_associated(mass)) then
      call set_thread_message('vci_model_create_separable: the mass argument is NULL'); return
    end if
    if (vci_size_problem(int(n), 0, int(ngaps)) /= '') then
      st = create_model('vci_model_create_separable', model, n, m, ngaps, vci_callbacks_c(), user)  ! its message
      vci_model_create_separable = st; return
    end if
    nm = n
    if (mass_kind == VCI_MASS_DENSE_C) nm = n * n
    call c_f_pointer(mass, mf, [nm])
    ! M checked once here (symmetric positive definite, finite) on a trial binding
    trial%n = n; trial%m = 0; trial%n_gaps = ngaps
    trial%mass_dense = mass_kind == VCI_MASS_DENSE_C
    allocate (trial%mass(nm), stat=st)
    if (st /= 0) then
      call set_thread_message('vci_model_create_separable: out of memory')
      vci_model_create_separable = VCI_ERR_MEMORY; return
    end if
    trial%mass = mf
    call bind_separable(probe, trial, st)
    if (st == VCI_ERR_MEMORY) then
      call set_thread_message('vci_model_create_separable: out of memory')
      vci_model_create_separable = VCI_ERR_MEMORY; return
    else if (st /= VCI_OK) then
      if (trial%mass_dense) then
        call set_thread_message('vci_model_create_separable: the mass matrix is not symmetric positive definite '// &
                                'and finite')
      else
        call set_thread_message('vci_model_create_separable: a diagonal mass entry is not positive and finite')
      end if
      return
    end if
    vci_model_create_separable = create_model('vci_model_create_separable', model, n, m, ngaps, vci_callbacks_c(), &
                                              user, scb=local, mass=trial%mass, mass_dense=trial%mass_dense)
  end function vci_model_create_separable

  !> The model_create entry points' first checks (`who`: the one called): model and cb not NULL;
  !> then *model = NULL. False (the thread's message says why) when the call must fail.
  logical function pointers_given(who, model, cb) result(ok)
    character(len=*), intent(in) :: who
    type(c_ptr), intent(in) :: model, cb
    ok = .false.
    if (.not. c_associated(model)) then
      call set_thread_message(who//': the model argument is NULL'); return
    end if
    call null_out(model)
    if (.not. c_associated(cb)) then
      call set_thread_message(who//': the callbacks argument is NULL'); return
    end if
    ok = .true.
  end function pointers_given

  !> pointers_given, then the versioned struct at cb (`struct`, initialised by `init`; this
  !> library's is `ours` bytes, its required members end at `least`): nbytes = cb->size must be a
  !> whole struct of some header, and members beyond `ours` (a newer header's) must be NULL.
  logical function callbacks_usable(who, model, cb, ours, least, struct, init, nbytes) result(ok)
    character(len=*), intent(in) :: who, struct, init
    type(c_ptr), intent(in) :: model, cb
    integer(c_size_t), intent(in) :: ours, least
    integer(c_size_t), intent(out) :: nbytes
    integer(c_size_t), pointer :: size_field
    integer(c_int8_t), pointer :: src(:)
    character(len=24) :: txt
    nbytes = 0
    ok = pointers_given(who, model, cb)
    if (.not. ok) return
    ok = .false.
    call c_f_pointer(cb, size_field)
    nbytes = size_field
    txt = size_text(nbytes)
    if (.not. whole_callbacks(nbytes, least)) then
      call set_thread_message(who//': cb->size = '//trim(txt)//' is not the size of a '//struct// &
                              ' (initialise it with '//init//')')
      return
    end if
    call c_f_pointer(cb, src, [nbytes])
    if (nbytes > ours) then
      ! built against a newer vci.h: fine as long as the members this library does not know are NULL
      if (any(src(ours + 1:nbytes) /= 0)) then
        call set_thread_message(who//': callbacks this library does not know are set (cb->size = '// &
                                trim(txt)//'; the program was built against a newer vci.h)')
        return
      end if
    end if
    ok = .true.
  end function callbacks_usable

  !> A versioned callbacks struct (size field, then function pointers) of nbytes: at least the
  !> required members, whole members only (a size between two members is no header's struct), and
  !> at most 4096 bytes (a garbage size is refused before anything is read).
  pure logical function whole_callbacks(nbytes, least) result(ok)
    integer(c_size_t), intent(in) :: nbytes, least
    integer(c_size_t) :: head
    head = c_sizeof(0_c_size_t)
    ok = nbytes >= least .and. nbytes <= 4096 .and. mod(nbytes - head, c_sizeof(c_null_funptr)) == 0
  end function whole_callbacks

  !> A size_t as C prints it (%zu): Fortran's c_size_t is signed, so SIZE_MAX would read -1.
  pure function size_text(nbytes) result(txt)
    integer(c_size_t), intent(in) :: nbytes
    character(len=24) :: txt
    integer, parameter :: wide = selected_int_kind(38)
    integer(wide) :: u
    u = int(nbytes, wide)
    if (u < 0) u = u + 2_wide**(8 * c_sizeof(nbytes))
    write (txt, '(i0)') u
  end function size_text

  !> *out = NULL for the handle pointer `out` (not NULL).
  subroutine null_out(out)
    type(c_ptr), intent(in) :: out
    type(c_ptr), pointer :: h
    call c_f_pointer(out, h)
    h = c_null_ptr
  end subroutine null_out

  !> The model_create entry points (`caller`: the one called): validate, allocate, register.
  !> With lcb: a continuous model (its callbacks already checked; fcb unused).
  !> With scb, mass, mass_dense: a separable model (checked by vci_model_create_separable).
  integer function create_model(caller, model, n, m, ngaps, fcb, user, lcb, scb, mass, mass_dense) result(status)
    character(len=*), intent(in) :: caller   !< the C entry point called, named in messages
    type(c_ptr), intent(in) :: model, user
    integer(c_int), intent(in) :: n, m, ngaps
    type(vci_callbacks_c), intent(in) :: fcb
    type(vci_lagrangian_callbacks_c), intent(in), optional :: lcb
    type(vci_separable_callbacks_c), intent(in), optional :: scb
    real(dp), intent(in), optional :: mass(:)
    logical, intent(in), optional :: mass_dense
    type(c_ptr), pointer :: out
    type(c_model_t), pointer :: mp
    type(c_integrator_t), pointer :: none
    character(len=64) :: what
    character(len=80) :: why
    integer :: st
    status = VCI_ERR_ARGUMENT
    why = vci_size_problem(int(n), int(m), int(ngaps))
    if (why /= '') then
      block
        character(len=VCI_MSG_LEN) :: msg
        write (msg, '(a,3(i0,a))') caller//': sizes n = ', n, ', m = ', m, ', ngaps = ', ngaps, &
          ' invalid ('//trim(why)//')'
        call set_thread_message(msg)
      end block
      return
    end if
    what = ''
    if (.not. present(lcb) .and. .not. present(scb)) then
      if (.not. c_associated(fcb%d1_ld)) what = 'd1_ld'
      if (.not. c_associated(fcb%d2_ld)) what = 'd2_ld'
      if (.not. c_associated(fcb%d3_ld)) what = 'd3_ld'
      if (m > 0 .and. .not. c_associated(fcb%constraint_forms)) what = 'constraint_forms (needed as m > 0)'
      if (m > 0 .and. .not. c_associated(fcb%discrete_constraint)) what = 'discrete_constraint (needed as m > 0)'
      if (ngaps > 0 .and. .not. c_associated(fcb%gaps)) what = 'gaps (needed as ngaps > 0)'
    end if
    if (what /= '') then
      call set_thread_message(caller//': callback '//trim(what)//' is NULL'); return
    end if
    ! walls given but none counted: the run would never see them (was: no impacts, status 0)
    if (ngaps == 0 .and. c_associated(fcb%gaps)) what = 'x'
    if (present(lcb)) then
      if (ngaps == 0 .and. c_associated(lcb%gaps)) what = 'x'
    end if
    if (present(scb)) then
      if (ngaps == 0 .and. c_associated(scb%gaps)) what = 'x'
    end if
    if (what /= '') then
      call set_thread_message(caller//': a gaps callback is given but ngaps = 0: its walls '// &
        'would never be seen; pass ngaps = the number of gap functions, or leave the callback NULL'); return
    end if
    allocate (mp, stat=st)
    if (st /= 0) then
      call set_thread_message(caller//': out of memory')
      status = VCI_ERR_MEMORY; return
    end if
    mp%n = n; mp%m = m; mp%n_gaps = ngaps
    mp%cb = fcb
    mp%user = user
    if (present(lcb)) then
      mp%continuous = .true.
      mp%lcb = lcb
    end if
    if (present(scb)) then   ! (continuous too: vci_set_scheme accepts it)
      mp%continuous = .true.; mp%separable = .true.
      mp%scb = scb; mp%mass = mass; mp%mass_dense = mass_dense
    end if
    none => null()
    call c_f_pointer(model, out)
    call lock_registry()
    out = register(KIND_MODEL, mp, none)
    call unlock_registry()
    if (.not. c_associated(out)) then
      deallocate (mp)
      call set_thread_message(caller//': too many live handles, or out of memory')
      status = VCI_ERR_MEMORY; return
    end if
    status = VCI_OK
  end function create_model

  !> int vci_model_declare_bandwidth(vci_model model, int bw, int check): the model's Hessian blocks
  !> vanish outside |i - j| <= bw (bw < 0: dense again); check != 0: the debug check of the band.
  !> Integrators created from the model afterwards use it (those made before keep their copy).
  integer(c_int) function vci_model_declare_bandwidth(model, bw, check) bind(C, name='vci_model_declare_bandwidth')
    type(c_ptr), value :: model
    integer(c_int), value :: bw, check
    integer :: i
    vci_model_declare_bandwidth = VCI_ERR_ARGUMENT
    call lock_registry()
    i = find_live(model, KIND_MODEL)
    if (i > 0) then
      if (slots(i)%model%separable) then
        i = -1
      else
        call slots(i)%model%declare_bandwidth(int(bw), check=check /= 0)
      end if
    end if
    call unlock_registry()
    if (i == 0) then
      call set_thread_message('vci_model_declare_bandwidth: not a live model handle'); return
    else if (i < 0) then
      call set_thread_message('vci_model_declare_bandwidth: a separable model has no declared bandwidth '// &
                              '(give its potential_hessian; the band is for vci_model_create and '// &
                              'vci_model_create_lagrangian models)'); return
    end if
    vci_model_declare_bandwidth = VCI_OK
  end function vci_model_declare_bandwidth

  !> void vci_model_destroy(vci_model *model): NULL-safe, sets *model = NULL. Integrators made
  !> from the model keep their own copy of it.
  subroutine vci_model_destroy(model) bind(C, name='vci_model_destroy')
    type(c_ptr), value :: model
    type(c_ptr), pointer :: h
    type(c_model_t), pointer :: mp
    integer :: i
    if (.not. c_associated(model)) return
    call c_f_pointer(model, h)
    if (.not. c_associated(h)) return
    mp => null()
    call lock_registry()
    i = find_live(h, KIND_MODEL)
    if (i > 0) then
      mp => slots(i)%model
      call unregister(i)
    end if
    call unlock_registry()
    if (associated(mp)) then
      deallocate (mp)
    else
      call set_thread_message('vci_model_destroy: not a live model handle (destroyed twice?); ignored')
    end if
    h = c_null_ptr
  end subroutine vci_model_destroy

  !> int vci_integrator_create(vci_integrator *integ, vci_model model, double h)
  integer(c_int) function vci_integrator_create(integ, model, h) bind(C, name='vci_integrator_create')
    type(c_ptr), value :: integ, model
    real(c_double), value :: h
    type(c_ptr), pointer :: out
    type(c_model_t), pointer :: none
    type(c_integrator_t), pointer :: ip
    integer :: stat, i
    vci_integrator_create = VCI_ERR_ARGUMENT
    if (.not. c_associated(integ)) then
      call set_thread_message('vci_integrator_create: the integ argument is NULL'); return
    end if
    call c_f_pointer(integ, out)
    out = c_null_ptr
    allocate (ip, stat=stat)
    if (stat /= 0) then
      call set_thread_message('vci_integrator_create: out of memory')
      vci_integrator_create = VCI_ERR_MEMORY; return
    end if
    ! the integrator's own copy of the model, taken under the lock (the model may be destroyed
    ! by another thread at the same time)
    call lock_registry()
    i = find_live(model, KIND_MODEL)
    if (i > 0) ip%model = slots(i)%model
    call unlock_registry()
    if (i == 0) then
      deallocate (ip)
      if (.not. c_associated(model)) then
        call set_thread_message('vci_integrator_create: the model handle is NULL')
      else
        call set_thread_message('vci_integrator_create: not a live model handle (destroyed, or not made by '// &
                                'vci_model_create or vci_model_create_lagrangian)')
      end if
      return
    end if
    call ip%model%record%clear()
    if (ip%model%separable) then
      call bind_separable(ip%sep, ip%model, stat)   ! (M was checked at creation)
      if (stat == VCI_OK) call ip%integ%create(ip%sep, real(h, dp), stat)
    else if (ip%model%continuous) then
      ip%lag%n = ip%model%n; ip%lag%m = ip%model%m; ip%lag%n_gaps = ip%model%n_gaps
      ip%lag%cb = ip%model%lcb
      ip%lag%user = ip%model%user
      ip%lag%record => ip%model%record
      call ip%lag%declare_bandwidth(ip%model%hessian_bandwidth, check=ip%model%check_bandwidth)
      call copy_pattern(ip%model, ip%lag)
      call ip%integ%create(ip%lag, real(h, dp), stat)
    else
      call ip%integ%create(ip%model, real(h, dp), stat)
    end if
    if (stat /= VCI_OK) then
      call set_thread_message('vci_integrator_create: '//trim(ip%integ%message_text()))
      deallocate (ip)
      vci_integrator_create = stat; return
    end if
    ip%obs%owner => ip
    none => null()
    call lock_registry()
    out = register(KIND_INTEGRATOR, none, ip)
    call unlock_registry()
    if (.not. c_associated(out)) then
      deallocate (ip)
      call set_thread_message('vci_integrator_create: too many live handles, or out of memory')
      vci_integrator_create = VCI_ERR_MEMORY; return
    end if
    vci_integrator_create = VCI_OK
  end function vci_integrator_create

  !> void vci_integrator_destroy(vci_integrator *integ): NULL-safe, sets *integ = NULL; closes
  !> output. The handle is dead at once; an integrator that is running a call (destroyed from one
  !> of its callbacks, or from another thread) is freed when that call returns.
  subroutine vci_integrator_destroy(integ) bind(C, name='vci_integrator_destroy')
    type(c_ptr), value :: integ
    type(c_ptr), pointer :: h
    type(c_integrator_t), pointer :: ip
    integer :: i
    logical :: free_now
    if (.not. c_associated(integ)) return
    call c_f_pointer(integ, h)
    if (.not. c_associated(h)) return
    ip => null()
    free_now = .false.
    call lock_registry()
    i = find_live(h, KIND_INTEGRATOR)
    if (i > 0) then
      ip => slots(i)%integ
      call unregister(i)
      if (ip%busy) then
        ip%destroy_pending = .true.
      else
        free_now = .true.
      end if
    end if
    call unlock_registry()
    if (i == 0) call set_thread_message('vci_integrator_destroy: not a live integrator handle (destroyed twice?); '// &
                                        'ignored')
    if (free_now) call free_integrator(ip)
    h = c_null_ptr
  end subroutine vci_integrator_destroy

  !> int vci_set_tolerances(vci_integrator integ, double atol, double rtol, int max_iterations)
  integer(c_int) function vci_set_tolerances(integ, atol, rtol, max_iterations) bind(C, name='vci_set_tolerances')
    type(c_ptr), value :: integ
    real(c_double), value :: atol, rtol
    integer(c_int), value :: max_iterations
    type(c_integrator_t), pointer :: ip
    integer :: stat
    call enter(integ, 'vci_set_tolerances', ip, stat)
    if (stat == VCI_OK) then
      call ip%integ%set_tolerances(real(atol, dp), real(rtol, dp), int(max_iterations), stat)
      call leave(ip)
    end if
    vci_set_tolerances = stat
  end function vci_set_tolerances

  !> int vci_set_impact_energy(vci_integrator integ, int mode): 0 discrete (default), 1 hamiltonian.
  integer(c_int) function vci_set_impact_energy(integ, mode) bind(C, name='vci_set_impact_energy')
    type(c_ptr), value :: integ
    integer(c_int), value :: mode
    type(c_integrator_t), pointer :: ip
    integer :: stat
    call enter(integ, 'vci_set_impact_energy', ip, stat)
    if (stat == VCI_OK) then
      call ip%integ%set_impact_energy(int(mode), stat)
      call leave(ip)
    end if
    vci_set_impact_energy = stat
  end function vci_set_impact_energy

  !> int vci_set_max_impacts(vci_integrator integ, int max_impacts): impacts allowed in one step.
  integer(c_int) function vci_set_max_impacts(integ, max_impacts) bind(C, name='vci_set_max_impacts')
    type(c_ptr), value :: integ
    integer(c_int), value :: max_impacts
    type(c_integrator_t), pointer :: ip
    integer :: stat
    call enter(integ, 'vci_set_max_impacts', ip, stat)
    if (stat == VCI_OK) then
      call ip%integ%set_max_impacts(int(max_impacts), stat)
      call leave(ip)
    end if
    vci_set_max_impacts = stat
  end function vci_set_max_impacts

  !> int vci_set_step_splits(vci_integrator integ, int max_splits): the safety net's bound (1: off).
  integer(c_int) function vci_set_step_splits(integ, max_splits) bind(C, name='vci_set_step_splits')
    type(c_ptr), value :: integ
    integer(c_int), value :: max_splits
    type(c_integrator_t), pointer :: ip
    integer :: stat
    call enter(integ, 'vci_set_step_splits', ip, stat)
    if (stat == VCI_OK) then
      call ip%integ%set_step_splits(int(max_splits), stat)
      call leave(ip)
    end if
    vci_set_step_splits = stat
  end function vci_set_step_splits

  !> int vci_set_poke_samples(vci_integrator integ, int on): the poke screen (1, the default) or not (0).
  integer(c_int) function vci_set_poke_samples(integ, on) bind(C, name='vci_set_poke_samples')
    type(c_ptr), value :: integ
    integer(c_int), value :: on
    type(c_integrator_t), pointer :: ip
    integer :: stat
    call enter(integ, 'vci_set_poke_samples', ip, stat)
    if (stat == VCI_OK) then
      if (on == 0 .or. on == 1) then
        call ip%integ%set_poke_samples(on == 1, stat)
      else
        stat = fail(ip, VCI_ERR_ARGUMENT, 'vci_set_poke_samples: on must be 0 or 1')
      end if
      call leave(ip)
    end if
    vci_set_poke_samples = stat
  end function vci_set_poke_samples

  !> int vci_set_scheme(vci_integrator integ, int scheme, int stages): the scheme of a continuous model.
  integer(c_int) function vci_set_scheme(integ, scheme, stages) bind(C, name='vci_set_scheme')
    type(c_ptr), value :: integ
    integer(c_int), value :: scheme, stages
    type(c_integrator_t), pointer :: ip
    integer :: stat
    call enter(integ, 'vci_set_scheme', ip, stat)
    if (stat == VCI_OK) then
      if (output_blocks_init(ip, 'vci_set_scheme', stat)) then
        continue
      else if (.not. ip%model%continuous) then
        stat = fail(ip, VCI_ERR_ARGUMENT, 'vci_set_scheme: the model is a discrete L_d (vci_model_create); '// &
                    'schemes discretise a continuous one (vci_model_create_lagrangian)')
      else
        call ip%integ%set_scheme(int(scheme), int(stages), stat)
      end if
      call leave(ip)
    end if
    vci_set_scheme = stat
  end function vci_set_scheme

  !> An output file holds one run from one initialisation: no new start while it has rows.
  logical function output_blocks_init(ip, who, stat)
    type(c_integrator_t), intent(inout) :: ip
    character(len=*), intent(in) :: who
    integer, intent(out) :: stat
    stat = VCI_OK
    output_blocks_init = allocated(ip%obs%output) .and. ip%obs%started
    if (output_blocks_init) stat = fail(ip, VCI_ERR_STATE, who//': the open output file holds the run so far; '// &
                                        'close it (vci_close_output) or open a new one before starting again')
  end function output_blocks_init

  !> int vci_init_from_pair(vci_integrator integ, double t0, const double *q0, const double *q1)
  integer(c_int) function vci_init_from_pair(integ, t0, q0, q1) bind(C, name='vci_init_from_pair')
    type(c_ptr), value :: integ, q0, q1
    real(c_double), value :: t0
    vci_init_from_pair = init_entry(integ, 'vci_init_from_pair', .true., t0, q0, q1)
  end function vci_init_from_pair

  !> int vci_init_from_momentum(vci_integrator integ, double t0, const double *q0, const double *p0)
  integer(c_int) function vci_init_from_momentum(integ, t0, q0, p0) bind(C, name='vci_init_from_momentum')
    type(c_ptr), value :: integ, q0, p0
    real(c_double), value :: t0
    vci_init_from_momentum = init_entry(integ, 'vci_init_from_momentum', .false., t0, q0, p0)
  end function vci_init_from_momentum

  !> The two init entry points (`who`): from the pair (q0 at t0, x1 = q1 at t0 + h) when from_pair,
  !> else from (q0, x1 = p0) at t0.
  integer function init_entry(integ, who, from_pair, t0, q0, x1) result(stat)
    type(c_ptr), intent(in) :: integ, q0, x1
    character(len=*), intent(in) :: who
    logical, intent(in) :: from_pair
    real(c_double), intent(in) :: t0
    type(c_integrator_t), pointer :: ip
    real(c_double), pointer :: a(:), b(:)
    call enter(integ, who, ip, stat)
    if (stat /= VCI_OK) return
    if (.not. (c_array(q0, ip%model%n, a) .and. c_array(x1, ip%model%n, b))) then
      call ip%integ%forget_state()
      stat = fail(ip, VCI_ERR_ARGUMENT, who//': q0 or '//merge('q1', 'p0', from_pair)//' is NULL')
    else if (.not. output_blocks_init(ip, who, stat)) then
      if (from_pair) then
        call ip%integ%init_from_pair(real(t0, dp), a, b, stat)
      else
        call ip%integ%init_from_momentum(real(t0, dp), a, b, stat)
      end if
      stat = after_call(ip, stat)
    end if
    call leave(ip)
  end function init_entry

  !> The output's run goes one way: refuse the other direction while it is open.
  logical function output_blocks_direction(ip, who, direction, stat)
    type(c_integrator_t), intent(inout) :: ip
    character(len=*), intent(in) :: who
    integer, intent(in) :: direction
    integer, intent(out) :: stat
    stat = VCI_OK
    output_blocks_direction = allocated(ip%obs%output) .and. ip%obs%started .and. &
                              (direction == 1 .or. direction == -1) .and. direction /= ip%obs%direction
    if (output_blocks_direction) stat = fail(ip, VCI_ERR_STATE, who//': the open output file holds a run in the '// &
      'other direction; close it (vci_close_output) or open a new one to integrate this way')
  end function output_blocks_direction

  !> int vci_step(vci_integrator integ, int direction)
  integer(c_int) function vci_step(integ, direction) bind(C, name='vci_step')
    type(c_ptr), value :: integ
    integer(c_int), value :: direction
    type(c_integrator_t), pointer :: ip
    integer :: stat, ostat
    character(len=VCI_MSG_LEN) :: cause   !< why the checkpoint for the output's start could not be taken
    call enter(integ, 'vci_step', ip, stat)
    cause = ''
    if (stat /= VCI_OK) then
      vci_step = stat; return
    end if
    if (.not. output_blocks_direction(ip, 'vci_step', int(direction), stat)) then
      ! a single step has no on_start of its own: the output's run starts with the first step
      ostat = 0
      if (allocated(ip%obs%output) .and. .not. ip%obs%started .and. ip%integ%is_initialized() .and. &
          (direction == 1 .or. direction == -1)) then
        if (ip%obs%wants_checkpoint()) then
          call ip%integ%checkpoint_to(ip%obs, ostat, cause)
        end if
        if (ostat == 0) call ip%obs%on_start(ip%integ%run_info(int(direction)), ip%integ%configuration(), &
                                             ip%integ%momentum(), ostat)
      end if
      if (ostat == VCI_ERR_MEMORY) then
        if (len_trim(cause) == 0) cause = output_message(ip)
        stat = fail(ip, VCI_ERR_MEMORY, 'vci_step: the output could not start the run: '//trim(cause))
      else if (ostat /= 0) then
        stat = fail(ip, VCI_ERR_IO, 'vci_step: the output could not start the run: '//trim(output_message(ip)))
      else
        call ip%integ%step(int(direction), stat, ip%obs)
        stat = after_call(ip, stat)
        call note_run_end(ip, stat)
      end if
    end if
    call leave(ip)
    vci_step = stat
  end function vci_step

  !> int vci_integrate(vci_integrator integ, int64_t nsteps, int direction)
  integer(c_int) function vci_integrate(integ, nsteps, direction) bind(C, name='vci_integrate')
    type(c_ptr), value :: integ
    integer(c_int64_t), value :: nsteps
    integer(c_int), value :: direction
    type(c_integrator_t), pointer :: ip
    integer :: stat
    call enter(integ, 'vci_integrate', ip, stat)
    if (stat /= VCI_OK) then
      vci_integrate = stat; return
    end if
    if (.not. output_blocks_direction(ip, 'vci_integrate', int(direction), stat)) then
      if (c_associated(ip%progress%fn)) then
        call ip%integ%integrate(int(nsteps, i8), int(direction), stat, ip%obs, ip%progress)
      else
        call ip%integ%integrate(int(nsteps, i8), int(direction), stat, ip%obs)
      end if
      stat = after_call(ip, stat)
      call note_run_end(ip, stat)
    end if
    call leave(ip)
    vci_integrate = stat
  end function vci_integrate

  !> int vci_set_progress(vci_integrator integ, vci_progress_fn fn, double interval, void *user)
  integer(c_int) function vci_set_progress(integ, fn, interval, user) bind(C, name='vci_set_progress')
    type(c_ptr), value :: integ, user
    type(c_funptr), value :: fn
    real(c_double), value :: interval
    type(c_integrator_t), pointer :: ip
    integer :: stat
    call enter(integ, 'vci_set_progress', ip, stat)
    if (stat /= VCI_OK) then
      vci_set_progress = stat; return
    end if
    if (.not. (interval >= 0.0_c_double .and. interval <= 1.0e9_c_double)) then
      call ip%integ%report_failure(VCI_ERR_ARGUMENT, 'vci_set_progress: interval must be a number of seconds in [0, 1e9]')
      stat = VCI_ERR_ARGUMENT
    else
      ip%progress%fn = fn; ip%progress%user = user; ip%progress%interval = real(interval, dp)
      call ip%integ%report_failure(VCI_OK, '')
    end if
    call leave(ip)
    vci_set_progress = stat
  end function vci_set_progress

  !> The output writer's own message, if it has one (fixed length: see vci_limits).
  function output_message(ip) result(msg)
    type(c_integrator_t), intent(in) :: ip
    character(len=VCI_MSG_LEN) :: msg
    msg = ''
#ifdef VCI_HAVE_HDF5
    if (allocated(ip%obs%output)) then
      select type (w => ip%obs%output)
      type is (vci_hdf5_writer_t)
        msg = trim(w%message)
      end select
    end if
#endif
  end function output_message

  !> Common checks of the getters: a live, initialised integrator (entered: leave it after).
  subroutine enter_ready(integ, who, ip, stat)
    type(c_ptr), intent(in) :: integ
    character(len=*), intent(in) :: who
    type(c_integrator_t), pointer, intent(out) :: ip
    integer, intent(out) :: stat
    call enter(integ, who, ip, stat)
    if (stat /= VCI_OK) return
    if (.not. ip%integ%is_initialized()) stat = fail(ip, VCI_ERR_STATE, who//': the integrator has no state yet '// &
                                                '(call vci_init_from_pair or vci_init_from_momentum)')
  end subroutine enter_ready

  !> int vci_get_state(vci_integrator integ, double *t, double *q, double *p): NULL outputs are skipped.
  integer(c_int) function vci_get_state(integ, t, q, p) bind(C, name='vci_get_state')
    type(c_ptr), value :: integ, t, q, p
    type(c_integrator_t), pointer :: ip
    real(c_double), pointer :: tt, a(:)
    integer :: stat
    call enter_ready(integ, 'vci_get_state', ip, stat)
    if (stat == VCI_OK) then
      if (c_associated(t)) then
        call c_f_pointer(t, tt); tt = ip%integ%time()
      end if
      if (c_array(q, ip%model%n, a)) a = ip%integ%configuration()
      if (c_array(p, ip%model%n, a)) a = ip%integ%momentum()
    end if
    if (associated(ip)) call leave(ip)
    vci_get_state = stat
  end function vci_get_state

  !> int vci_get_multipliers(vci_integrator integ, double *lambda /* [m] */)
  integer(c_int) function vci_get_multipliers(integ, lambda) bind(C, name='vci_get_multipliers')
    type(c_ptr), value :: integ, lambda
    type(c_integrator_t), pointer :: ip
    real(c_double), pointer :: a(:)
    integer :: stat
    call enter_ready(integ, 'vci_get_multipliers', ip, stat)
    if (stat == VCI_OK) then
      if (ip%model%m > 0) then
        if (c_array(lambda, ip%model%m, a)) then
          a = ip%integ%multipliers()
        else
          stat = fail(ip, VCI_ERR_ARGUMENT, 'vci_get_multipliers: lambda is NULL')
        end if
      end if
    end if
    if (associated(ip)) call leave(ip)
    vci_get_multipliers = stat
  end function vci_get_multipliers

  !> int vci_get_energy(vci_integrator integ, double *energy): E_d of the last step.
  integer(c_int) function vci_get_energy(integ, energy) bind(C, name='vci_get_energy')
    type(c_ptr), value :: integ, energy
    type(c_integrator_t), pointer :: ip
    real(c_double), pointer :: e
    integer :: stat
    call enter_ready(integ, 'vci_get_energy', ip, stat)
    if (stat == VCI_OK) then
      if (c_associated(energy)) then
        call c_f_pointer(energy, e)
        e = ip%integ%energy()
      else
        stat = fail(ip, VCI_ERR_ARGUMENT, 'vci_get_energy: energy is NULL')
      end if
    end if
    if (associated(ip)) call leave(ip)
    vci_get_energy = stat
  end function vci_get_energy

  !> int vci_get_index(vci_integrator integ, int64_t *k): index of the current state (t = t0 + k h).
  integer(c_int) function vci_get_index(integ, k) bind(C, name='vci_get_index')
    type(c_ptr), value :: integ, k
    type(c_integrator_t), pointer :: ip
    integer(c_int64_t), pointer :: kk
    integer :: stat
    call enter_ready(integ, 'vci_get_index', ip, stat)
    if (stat == VCI_OK) then
      if (c_associated(k)) then
        call c_f_pointer(k, kk)
        kk = int(ip%integ%step_index(), c_int64_t)
      else
        stat = fail(ip, VCI_ERR_ARGUMENT, 'vci_get_index: k is NULL')
      end if
    end if
    if (associated(ip)) call leave(ip)
    vci_get_index = stat
  end function vci_get_index

  !> int vci_get_stats(vci_integrator integ, int64_t *steps, int64_t *impacts, int64_t *newton_iterations)
  integer(c_int) function vci_get_stats(integ, steps, impacts, newton_iterations) bind(C, name='vci_get_stats')
    type(c_ptr), value :: integ, steps, impacts, newton_iterations
    type(c_integrator_t), pointer :: ip
    type(vci_stats_t) :: stats
    integer :: stat
    call enter(integ, 'vci_get_stats', ip, stat)
    if (stat == VCI_OK) then
      stats = ip%integ%statistics()
      call put_count(steps, stats%steps)
      call put_count(impacts, stats%impacts)
      call put_count(newton_iterations, stats%newton_iterations)
      call leave(ip)
    end if
    vci_get_stats = stat
  contains
    subroutine put_count(p, v)
      type(c_ptr), intent(in) :: p
      integer(i8), intent(in) :: v
      integer(c_int64_t), pointer :: l
      if (.not. c_associated(p)) return
      call c_f_pointer(p, l)
      l = int(v, c_int64_t)
    end subroutine put_count
  end function vci_get_stats

  !> int vci_get_energy_fallbacks(vci_integrator integ, int64_t *count): soft impacts where the
  !> discrete energy condition was blended with H or H(q, p) was kept instead (docs/DESIGN.md §2).
  integer(c_int) function vci_get_energy_fallbacks(integ, count) bind(C, name='vci_get_energy_fallbacks')
    type(c_ptr), value :: integ, count
    vci_get_energy_fallbacks = get_count(integ, count, 'vci_get_energy_fallbacks')
  end function vci_get_energy_fallbacks

  !> int vci_get_irreversible_impacts(vci_integrator integ, int64_t *count): impacts whose energy
  !> condition could not be tied to the sub-step that leaves them up to the next wall of the step
  !> (docs/BACKWARD.md, "Impacts that cannot be tied").
  integer(c_int) function vci_get_irreversible_impacts(integ, count) bind(C, name='vci_get_irreversible_impacts')
    type(c_ptr), value :: integ, count
    vci_get_irreversible_impacts = get_count(integ, count, 'vci_get_irreversible_impacts')
  end function vci_get_irreversible_impacts

  !> The getters of one statistics counter each (fname names the getter, and so the counter):
  !> *count (when count is not NULL) from the integrator's statistics.
  integer(c_int) function get_count(integ, count, fname) result(stat)
    type(c_ptr), value :: integ, count
    character(len=*), intent(in) :: fname
    type(c_integrator_t), pointer :: ip
    type(vci_stats_t) :: stats
    integer(c_int64_t), pointer :: l
    call enter(integ, fname, ip, stat)
    if (stat /= VCI_OK) return
    if (c_associated(count)) then
      stats = ip%integ%statistics()
      call c_f_pointer(count, l)
      select case (fname)
      case ('vci_get_energy_fallbacks')
        l = int(stats%energy_fallbacks, c_int64_t)
      case ('vci_get_irreversible_impacts')
        l = int(stats%irreversible_impacts, c_int64_t)
      end select
    end if
    call leave(ip)
  end function get_count

  !> int vci_get_split_steps(vci_integrator integ, int64_t *steps, int64_t *largest): steps the
  !> safety net took as equal sub-steps, and the most sub-steps one of them needed.
  integer(c_int) function vci_get_split_steps(integ, steps, largest) bind(C, name='vci_get_split_steps')
    type(c_ptr), value :: integ, steps, largest
    type(c_integrator_t), pointer :: ip
    type(vci_stats_t) :: stats
    integer :: stat
    integer(c_int64_t), pointer :: l
    call enter(integ, 'vci_get_split_steps', ip, stat)
    if (stat == VCI_OK) then
      stats = ip%integ%statistics()
      if (c_associated(steps)) then
        call c_f_pointer(steps, l)
        l = int(stats%split_steps, c_int64_t)
      end if
      if (c_associated(largest)) then
        call c_f_pointer(largest, l)
        l = int(stats%largest_split, c_int64_t)
      end if
      call leave(ip)
    end if
    vci_get_split_steps = stat
  end function vci_get_split_steps

  !> int vci_set_bordered_impacts(vci_integrator integ, int on, int min_unknowns): impact stages by
  !> bordering (on = 1, the default) or whole (0); min_unknowns >= 2 sets the smallest bordered stage
  !> system, 0 keeps the current one (vci_integrator_t%set_bordered_impacts).
  integer(c_int) function vci_set_bordered_impacts(integ, on, min_unknowns) bind(C, name='vci_set_bordered_impacts')
    type(c_ptr), value :: integ
    integer(c_int), value :: on, min_unknowns
    type(c_integrator_t), pointer :: ip
    integer :: stat
    call enter(integ, 'vci_set_bordered_impacts', ip, stat)
    if (stat /= VCI_OK) then
      vci_set_bordered_impacts = stat; return
    end if
    if ((on /= 0 .and. on /= 1) .or. min_unknowns == 1 .or. min_unknowns < 0) then
      stat = VCI_ERR_ARGUMENT
      call ip%integ%report_failure(stat, 'vci_set_bordered_impacts: on must be 0 or 1 and min_unknowns 0 '// &
                                   '(keep) or at least 2')
    else
      if (min_unknowns == 0) then
        call ip%integ%set_bordered_impacts(on == 1)
      else
        call ip%integ%set_bordered_impacts(on == 1, int(min_unknowns))
      end if
      call ip%integ%report_failure(VCI_OK, '')
    end if
    call leave(ip)
    vci_set_bordered_impacts = stat
  end function vci_set_bordered_impacts

  !> int vci_get_bordered_directions(vci_integrator integ, int64_t *count): impact-stage Newton
  !> directions solved by bordering over the integrator's life.
  integer(c_int) function vci_get_bordered_directions(integ, count) bind(C, name='vci_get_bordered_directions')
    type(c_ptr), value :: integ, count
    type(c_integrator_t), pointer :: ip
    type(vci_stats_t) :: stats
    integer :: stat
    integer(c_int64_t), pointer :: l
    call enter(integ, 'vci_get_bordered_directions', ip, stat)
    if (stat == VCI_OK) then
      if (c_associated(count)) then
        stats = ip%integ%statistics()
        call c_f_pointer(count, l)
        l = int(stats%bordered_directions, c_int64_t)
      else
        stat = VCI_ERR_ARGUMENT
        call ip%integ%report_failure(stat, 'vci_get_bordered_directions: count is NULL')
      end if
      call leave(ip)
    end if
    vci_get_bordered_directions = stat
  end function vci_get_bordered_directions

  !> int vci_set_impact_callback(vci_integrator integ, vci_impact_fn fn, void *user): NULL fn removes it.
  integer(c_int) function vci_set_impact_callback(integ, fn, user) bind(C, name='vci_set_impact_callback')
    type(c_ptr), value :: integ, user
    type(c_funptr), value :: fn
    type(c_integrator_t), pointer :: ip
    integer :: stat
    call enter(integ, 'vci_set_impact_callback', ip, stat)
    if (stat == VCI_OK) then
      ip%obs%impact_fn = fn
      ip%obs%user = user
      call leave(ip)
    end if
    vci_set_impact_callback = stat
  end function vci_set_impact_callback

  !> int vci_open_output(vci_integrator integ, const char *path): HDF5 trajectory file (replaced if
  !> it exists); VCI_ERR_IO when the library was built without HDF5.
  integer(c_int) function vci_open_output(integ, path) bind(C, name='vci_open_output')
    type(c_ptr), value :: integ, path
    vci_open_output = open_output_entry(integ, path, 'vci_open_output', .false., 1, 0)
  end function vci_open_output

  !> int vci_open_output_every(vci_integrator integ, const char *path, int every, int compress):
  !> vci_open_output storing every `every`-th state (and the run's last), gzip level `compress`
  !> (0: none) with shuffle (docs/OUTPUT.md).
  integer(c_int) function vci_open_output_every(integ, path, every, compress) bind(C, name='vci_open_output_every')
    type(c_ptr), value :: integ, path
    integer(c_int), value :: every, compress
    vci_open_output_every = open_output_entry(integ, path, 'vci_open_output_every', .false., int(every), int(compress))
  end function vci_open_output_every

  !> int vci_append_output(vci_integrator integ, const char *path): continue the HDF5 file PATH
  !> (written by vci_open_output, the Fortran writer or the examples' --output) with the later
  !> steps; the run must go on from the file's last state, in its direction (vci_restore_from_file).
  integer(c_int) function vci_append_output(integ, path) bind(C, name='vci_append_output')
    type(c_ptr), value :: integ, path
    vci_append_output = open_output_entry(integ, path, 'vci_append_output', .true., 0, 0)
  end function vci_append_output

  !> A C string as a Fortran one; false (and a failure recorded on ip) when NULL, empty or there is
  !> no memory for the copy.
  logical function c_path(ip, who, path, fpath) result(ok)
    type(c_integrator_t), intent(inout) :: ip
    character(len=*), intent(in) :: who
    type(c_ptr), intent(in) :: path
    character(len=:), allocatable, intent(out) :: fpath
    character(kind=c_char), pointer :: chars(:)
    integer :: i, nc, stat
    ok = .false.
    if (.not. c_associated(path)) then
      stat = fail(ip, VCI_ERR_ARGUMENT, who//': path is NULL'); return
    end if
    nc = int(min(c_strlen(path), int(huge(1), c_size_t)))
    if (nc == 0) then
      stat = fail(ip, VCI_ERR_ARGUMENT, who//': path is empty'); return
    end if
    call c_f_pointer(path, chars, [nc])
    allocate (character(len=nc) :: fpath, stat=stat)   ! (a C string of any length: not tiny)
    if (stat /= 0) then
      stat = fail(ip, VCI_ERR_MEMORY, who//': no memory for a copy of the path'); return
    end if
    do i = 1, nc
      fpath(i:i) = chars(i)
    end do
    ok = .true.
  end function c_path

  !> vci_open_output(_every) (a new file, replacing PATH, every `every`-th state, gzip level
  !> `compress`) and vci_append_output (`append`: continue PATH with the file's own settings).
  integer function open_output_entry(integ, path, who, append, every, compress) result(stat)
    type(c_ptr), intent(in) :: integ, path
    character(len=*), intent(in) :: who
    logical, intent(in) :: append
    integer, intent(in) :: every, compress
    type(c_integrator_t), pointer :: ip
    character(len=:), allocatable :: fpath
    call enter(integ, who, ip, stat)
    if (stat /= VCI_OK) return
    if (.not. append .and. (every < 1 .or. every > 2**30)) then   ! the HDF5 writer's VCI_HDF5_EVERY_MAX
      stat = fail(ip, VCI_ERR_ARGUMENT, who//': every must be in [1, 2^30]')
    else if (.not. append .and. (compress < 0 .or. compress > 9)) then
      stat = fail(ip, VCI_ERR_ARGUMENT, who//': compress must be a gzip level in [0, 9] (0: none)')
    else if (.not. c_path(ip, who, path, fpath)) then
      stat = ip%integ%status()
    else
      stat = close_output(ip)
      if (stat /= VCI_OK) stat = fail(ip, stat, who//': the previous output file could not be finished')
    end if
    if (stat == VCI_OK) then
#ifdef VCI_HAVE_HDF5
      block
        type(vci_hdf5_writer_t), allocatable :: w
        allocate (w, stat=stat)
        if (stat /= 0) then
          stat = fail(ip, VCI_ERR_MEMORY, who//': out of memory')
        else
          call lock_io()
          if (append) then
            call w%open(fpath, stat, append=.true.)
          else
            call w%open(fpath, stat, overwrite=.true., every=every, compress=compress)
          end if
          call unlock_io()
          if (stat /= VCI_OK) then
            stat = fail(ip, VCI_ERR_IO, who//': '//trim(w%message))
          else
            call move_alloc(w, ip%obs%output)
            ip%obs%started = .false.
            ip%obs%direction = 0
            ip%obs%run_status = VCI_OK; ip%obs%run_message = ''
          end if
        end if
      end block
#else
      stat = fail(ip, VCI_ERR_IO, who//': cannot write '//fpath// &
                  ': this vci library was built without HDF5 (configure with -DVCI_WITH_HDF5=ON)')
#endif
    end if
    call leave(ip)
  end function open_output_entry

  !> int vci_restore_from_file(vci_integrator integ, const char *path): start from the last state
  !> of an HDF5 file of this library. With the checkpoint the writer stores at every flush (the
  !> last row's state and the solver's memory) the run continues bit for bit; a file without one
  !> gives its last (t, q, p) at index 0, as vci_init_from_momentum would.
  integer(c_int) function vci_restore_from_file(integ, path) bind(C, name='vci_restore_from_file')
    type(c_ptr), value :: integ, path
    character(len=*), parameter :: who = 'vci_restore_from_file'
    type(c_integrator_t), pointer :: ip
    character(len=:), allocatable :: fpath
    integer :: stat
    call enter(integ, who, ip, stat)
    if (stat /= VCI_OK) then
      vci_restore_from_file = stat; return
    end if
    if (.not. c_path(ip, who, path, fpath)) then
      stat = ip%integ%status()
    else if (.not. output_blocks_init(ip, who, stat)) then
#ifdef VCI_HAVE_HDF5
      block
        type(vci_checkpoint_t) :: cp
        character(len=VCI_MSG_LEN) :: msg
        character(len=160) :: why
        call lock_io()
        call vci_hdf5_read_checkpoint(fpath, cp, stat, msg)
        call unlock_io()
        if (stat /= VCI_OK) then
          call ip%integ%forget_state()
          stat = fail(ip, VCI_ERR_IO, who//': '//trim(msg))
        else if (size(cp%q) /= ip%model%n .or. size(cp%lambda) /= ip%model%m) then
          call ip%integ%forget_state()
          write (why, '(2(a,i0),a,2(i0,a))') ': the file holds n = ', size(cp%q), ', m = ', size(cp%lambda), &
            '; the model has n = ', ip%model%n, ', m = ', ip%model%m, ' (a file of another model)'
          stat = fail(ip, VCI_ERR_ARGUMENT, who//': '//fpath//trim(why))
        else if (cp%h /= ip%integ%step_length()) then
          call ip%integ%forget_state()
          write (why, '(a,es24.17,a,es24.17,a)') ': the file''s step length h = ', cp%h, &
            ' differs from the integrator''s h = ', ip%integ%step_length(), ' (create it with the file''s h)'
          stat = fail(ip, VCI_ERR_ARGUMENT, who//': '//fpath//trim(why))
        else
          call ip%integ%restore(cp, stat)
          stat = after_call(ip, stat)
          if (stat /= VCI_OK) stat = fail(ip, stat, who//': '//fpath//': '//trim(ip%integ%message_text()))
        end if
      end block
#else
      call ip%integ%forget_state()
      stat = fail(ip, VCI_ERR_IO, who//': cannot read '//fpath// &
                  ': this vci library was built without HDF5 (configure with -DVCI_WITH_HDF5=ON)')
#endif
    end if
    call leave(ip)
    vci_restore_from_file = stat
  end function vci_restore_from_file

  !> int vci_close_output(vci_integrator integ): finish and close the output file (no-op without one).
  integer(c_int) function vci_close_output(integ) bind(C, name='vci_close_output')
    type(c_ptr), value :: integ
    type(c_integrator_t), pointer :: ip
    integer :: stat
    character(len=VCI_MSG_LEN) :: why
    call enter(integ, 'vci_close_output', ip, stat)
    if (stat == VCI_OK) then
      why = output_message(ip)
      stat = close_output(ip)
      if (stat == VCI_ERR_MEMORY) then
        stat = fail(ip, stat, 'vci_close_output: no memory for the last state''s checkpoint: the file was '// &
                    'finished without it')
      else if (stat /= VCI_OK) then
        stat = fail(ip, stat, 'vci_close_output: the output file could not be finished: '//trim(why))
      end if
      call leave(ip)
    end if
    vci_close_output = stat
  end function vci_close_output

  !> int vci_last_error(vci_integrator integ, char *buffer, int size): the message of the last
  !> call on integ (empty after success), or with integ == NULL the calling thread's last failure
  !> that had no live integrator to hold it. Truncated to size - 1 characters and NUL-terminated.
  integer(c_int) function vci_last_error(integ, buffer, size) bind(C, name='vci_last_error')
    type(c_ptr), value :: integ, buffer
    integer(c_int), value :: size
    character(kind=c_char), pointer :: out(:)
    character(len=VCI_MSG_LEN) :: msg
    integer :: i, nc
    if (.not. c_associated(buffer) .or. size < 1) then
      vci_last_error = VCI_ERR_ARGUMENT; return
    end if
    vci_last_error = VCI_OK
    if (.not. c_associated(integ)) then
      msg = thread_message()
    else
      ! under the lock: no call on it can start (and write its message) while it is copied
      call lock_registry()
      i = find_live(integ, KIND_INTEGRATOR)
      if (i == 0) then
        msg = 'vci_last_error: not a live integrator handle (destroyed, or not made by vci_integrator_create)'
        vci_last_error = VCI_ERR_ARGUMENT
      else if (slots(i)%integ%busy) then
        msg = 'vci_last_error: the integrator is busy (a call on it is running)'
        vci_last_error = VCI_ERR_STATE
      else
        msg = slots(i)%integ%integ%message_text()
      end if
      call unlock_registry()
    end if
    call c_f_pointer(buffer, out, [size])
    nc = min(len_trim(msg), size - 1)
    do i = 1, nc
      out(i) = msg(i:i)
    end do
    out(nc + 1) = c_null_char
  end function vci_last_error

  !> const char *vci_status_string(int status): a static, NUL-terminated description.
  type(c_ptr) function vci_status_string(status) bind(C, name='vci_status_string')
    integer(c_int), value :: status
    integer :: i
    i = N_STATUS + 1    ! 'unknown status'
    if (status >= 0 .and. status <= N_STATUS) i = int(status)
    vci_status_string = c_loc(status_text(i))
  end function vci_status_string

  !> int vci_check_model(vci_model model, const double *q, const double *v, double h, double tol,
  !>                     int *passed, double *worst, char *report, int size): the model checker
  !> (vci_model_check) on a copy of the model; report (may be NULL) gets one line per comparison.
  integer(c_int) function capi_check_model(model, q, v, h, tol, passed, worst, report, size) &
      bind(C, name='vci_check_model')
    type(c_ptr), value :: model, q, v, passed, worst, report
    real(c_double), value :: h, tol
    integer(c_int), value :: size
    type(c_model_t), target :: mc
    type(c_lagrangian_t) :: lag
    type(c_separable_t) :: sep
    type(vci_check_report_t) :: rep
    real(c_double), pointer :: qf(:), vf(:)
    integer(c_int), pointer :: passed_f
    real(c_double), pointer :: worst_f
    character(kind=c_char), pointer :: out(:)
    character(len=VCI_MSG_LEN) :: msg
    character(len=:), allocatable :: text
    integer :: i, stat
    capi_check_model = VCI_ERR_ARGUMENT
    if (.not. (c_associated(q) .and. c_associated(v) .and. c_associated(passed) .and. c_associated(worst))) then
      call set_thread_message('vci_check_model: q, v, passed and worst must not be NULL'); return
    end if
    if (c_associated(report) .and. size < 1) then
      call set_thread_message('vci_check_model: report given with size < 1'); return
    end if
    call lock_registry()
    i = find_live(model, KIND_MODEL)
    if (i > 0) mc = slots(i)%model
    call unlock_registry()
    if (i == 0) then
      call set_thread_message('vci_check_model: not a live model handle'); return
    end if
    call mc%record%clear()
    call c_f_pointer(q, qf, [mc%n]); call c_f_pointer(v, vf, [mc%n])
    if (mc%separable) then
      msg = ''
      call bind_separable(sep, mc, stat)
      if (stat == VCI_OK) &
        call vci_check_model(sep, qf, vf, real(h, dp), rep, stat, msg, tol=merge(real(tol, dp), rep%tol, tol > 0))
      if (stat /= VCI_OK .and. msg == '') msg = 'vci_check_model: the mass matrix could not be set'
    else if (mc%continuous) then
      lag%n = mc%n; lag%m = mc%m; lag%n_gaps = mc%n_gaps
      lag%cb = mc%lcb; lag%user = mc%user; lag%record => mc%record
      call vci_check_model(lag, qf, vf, real(h, dp), rep, stat, msg, tol=merge(real(tol, dp), rep%tol, tol > 0))
    else
      call vci_check_model(mc, qf, vf, real(h, dp), rep, stat, msg, tol=merge(real(tol, dp), rep%tol, tol > 0))
    end if
    capi_check_model = stat
    if (stat /= VCI_OK) then
      call set_thread_message(msg); return
    end if
    call c_f_pointer(passed, passed_f); call c_f_pointer(worst, worst_f)
    passed_f = merge(1_c_int, 0_c_int, rep%passed); worst_f = rep%worst
    if (.not. c_associated(report)) return
    text = ''
    do i = 1, rep%count
      text = text//trim(rep%line(i))//new_line('a')
    end do
    call c_f_pointer(report, out, [size])
    do i = 1, min(len(text), size - 1)
      out(i) = text(i:i)
    end do
    out(min(len(text), size - 1) + 1) = c_null_char
  end function capi_check_model

  !> int vci_model_declare_pattern(vci_model model, int n, const int *colptr, const int *rowind,
  !> int check): the model's Hessian blocks vanish outside a sparse pattern, given 0-based in
  !> compressed columns and checked strictly here (the Fortran declare_pattern is lenient: any order,
  !> repeats); n = 0 withdraws it. Integrators created from the model afterwards use it.
  integer(c_int) function vci_model_declare_pattern(model, n, colptr, rowind, check) &
      bind(C, name='vci_model_declare_pattern')
    type(c_ptr), value :: model, colptr, rowind
    integer(c_int), value :: n, check
    character(len=*), parameter :: who = 'vci_model_declare_pattern: '
    integer(c_int), pointer :: cp(:), ri(:)
    integer(c_int), target :: empty(0)
    integer, allocatable :: cp1(:), ri1(:)
    character(len=200) :: why
    integer :: i, nnz, st
    vci_model_declare_pattern = VCI_ERR_ARGUMENT
    why = ''
    nnz = 0
    if (n /= 0 .and. .not. sparse_available_f()) then
      why = 'this vci was built without the sparse solver (CMake VCI_SPARSE=OFF; SuiteSparse KLU, '// &
            'Debian libsuitesparse-dev); vci_sparse_available() returns 0'
    else if (n < 0) then
      write (why, '(a,i0,a)') 'n = ', n, ' (the model''s n, or 0 to withdraw the pattern)'
    else if (n > 0 .and. .not. c_associated(colptr)) then
      why = 'colptr is NULL'
    else if (n > 0) then
      call c_f_pointer(colptr, cp, [n + 1])
      nnz = max(cp(n + 1), 0)
      if (nnz > 0 .and. .not. c_associated(rowind)) then
        why = 'rowind is NULL (colptr[n] > 0)'
      else
        if (nnz > 0) call c_f_pointer(rowind, ri, [nnz])
        if (nnz == 0) ri => empty
        call pattern_arrays_error(int(n), cp, ri, 0, 'colptr', 'rowind', why)
      end if
    end if
    if (why /= '') then
      call set_thread_message(who//trim(why)); return
    end if
    allocate (cp1(merge(0, n + 1, n == 0)), ri1(nnz), stat=st)
    if (st /= 0) then
      call set_thread_message(who//'out of memory')
      vci_model_declare_pattern = VCI_ERR_MEMORY; return
    end if
    if (n > 0) then
      cp1 = cp + 1
      if (nnz > 0) ri1 = ri + 1
    end if
    st = VCI_OK
    call lock_registry()
    i = find_live(model, KIND_MODEL)
    if (i > 0) then
      if (slots(i)%model%separable) then
        why = 'a separable model has no declared pattern (give its potential_hessian; the pattern is for '// &
              'vci_model_create and vci_model_create_lagrangian models)'
      else if (n /= 0 .and. n /= slots(i)%model%n) then
        write (why, '(a,i0,a,i0,a)') 'n = ', n, ', but the model has n = ', slots(i)%model%n, ' (or 0 to withdraw)'
      else
        call slots(i)%model%declare_pattern(cp1, ri1, check=check /= 0)
        if (slots(i)%model%pattern_status /= 0) then
          why = slots(i)%model%pattern_message
          if (index(why, 'memory') > 0) st = VCI_ERR_MEMORY
          call slots(i)%model%declare_pattern([integer ::], [integer ::])
        end if
      end if
    else
      why = 'not a live model handle'
    end if
    call unlock_registry()
    if (why /= '') then
      call set_thread_message(who//trim(why))
      if (st == VCI_ERR_MEMORY) vci_model_declare_pattern = VCI_ERR_MEMORY
      return
    end if
    vci_model_declare_pattern = VCI_OK
  end function vci_model_declare_pattern

  !> int vci_sparse_available(void): 1 if built with the sparse solver (VCI_SPARSE, KLU), else 0.
  integer(c_int) function vci_sparse_available() bind(C, name='vci_sparse_available')
    vci_sparse_available = merge(1_c_int, 0_c_int, sparse_available_f())
  end function vci_sparse_available

  !> The declared pattern of a C model handed to the continuous model the integrator runs.
  subroutine copy_pattern(from, to)
    type(c_model_t), intent(in) :: from
    type(c_lagrangian_t), intent(inout) :: to
    to%hessian_pattern = from%hessian_pattern; to%check_pattern = from%check_pattern
    to%pattern_status = from%pattern_status; to%pattern_message = from%pattern_message
  end subroutine copy_pattern

  !> int vci_version(void): major*10000 + minor*100 + patch.
  integer(c_int) function vci_version() bind(C, name='vci_version')
    vci_version = VCI_VERSION_NUMBER
  end function vci_version
end module vci_capi
