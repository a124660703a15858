!> The C ABI of vci (include/vci.h): the only module that speaks iso_c_binding for C callers.
!>
!> Handles are c_loc of allocated Fortran objects and are checked against a registry of live
!> handles before they are dereferenced, so NULL, destroyed or foreign handles give
!> VCI_ERR_ARGUMENT instead of a crash. The C model is one more extension of vci_model_t: it holds
!> the C function pointers and the user pointer and dispatches with c_f_procpointer (no internal
!> procedures, hence no trampolines and no executable stack). A model is reference counted, so an
!> integrator keeps it alive after vci_model_destroy.
!>
!> Errors that cannot be attached to a live integrator (bad handles, failed creation) go to a
!> library-wide message read with vci_last_error(NULL, ...). The registry and that message are
!> global state: create/destroy and calls with invalid handles are not thread-safe.
module vci_capi
  use, intrinsic :: iso_c_binding
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use vci_kinds, only: dp, i8
  use vci_status
  use vci_model, only: vci_model_t
  use vci_limits, only: vci_size_problem
  use vci_observer, only: vci_observer_t, vci_run_info_t, vci_impact_t
  use vci_integrator, only: vci_integrator_t, VCI_IMPACT_DISCRETE, VCI_IMPACT_HAMILTONIAN
  use vci, only: VCI_VERSION_NUMBER
#ifdef VCI_HAVE_HDF5
  use vci_hdf5_output, only: vci_hdf5_writer_t
#endif
  implicit none
  private

  public :: vci_model_create, vci_model_destroy, vci_integrator_create, vci_integrator_destroy
  public :: vci_set_tolerances, vci_set_impact_energy, vci_set_max_impacts
  public :: vci_init_from_pair, vci_init_from_momentum, vci_step, vci_integrate
  public :: vci_get_state, vci_get_multipliers, vci_get_energy, vci_get_index, vci_get_stats
  public :: vci_set_impact_callback, vci_open_output, vci_close_output
  public :: vci_last_error, vci_status_string, vci_version

  !> Mirror of `struct vci_callbacks` in vci.h (same order; new members only at the end).
  type, bind(C) :: vci_callbacks_c
    type(c_funptr) :: d1_ld, d2_ld, d3_ld, mixed_hessian, constraint_forms, discrete_constraint, &
                      gaps, gap_gradients, energy
  end type vci_callbacks_c

  !> The C signatures of the callbacks (vci.h); each returns 0 on success.
  abstract interface
    integer(c_int) function c_ld_grad_fn(n, q, v, h, out, user) bind(C)
      import :: c_int, c_double, c_ptr
      integer(c_int), value :: n
      real(c_double), intent(in) :: q(*), v(*)
      real(c_double), value :: h
      real(c_double), intent(inout) :: out(*)
      type(c_ptr), value :: user
    end function c_ld_grad_fn
    integer(c_int) function c_forms_fn(n, m, q, omega, user) bind(C)
      import :: c_int, c_double, c_ptr
      integer(c_int), value :: n, m
      real(c_double), intent(in) :: q(*)
      real(c_double), intent(inout) :: omega(*)
      type(c_ptr), value :: user
    end function c_forms_fn
    integer(c_int) function c_dconstraint_fn(n, m, base, other, h, out, user) bind(C)
      import :: c_int, c_double, c_ptr
      integer(c_int), value :: n, m
      real(c_double), intent(in) :: base(*), other(*)
      real(c_double), value :: h
      real(c_double), intent(inout) :: out(*)
      type(c_ptr), value :: user
    end function c_dconstraint_fn
    integer(c_int) function c_energy_fn(n, q, p, e, user) bind(C)
      import :: c_int, c_double, c_ptr
      integer(c_int), value :: n
      real(c_double), intent(in) :: q(*), p(*)
      real(c_double), intent(inout) :: e(*)
      type(c_ptr), value :: user
    end function c_energy_fn
    integer(c_int) function c_impact_fn(t, alpha, gap_index, q, impulse, user) bind(C)
      import :: c_int, c_double, c_ptr
      real(c_double), value :: t, alpha
      integer(c_int), value :: gap_index
      real(c_double), intent(in) :: q(*)
      real(c_double), value :: impulse
      type(c_ptr), value :: user
    end function c_impact_fn
  end interface

  interface
    pure integer(c_size_t) function c_strlen(s) bind(C, name='strlen')
      import :: c_size_t, c_ptr
      type(c_ptr), value, intent(in) :: s
    end function c_strlen
  end interface

  !> The model behind a `vci_model` handle: C function pointers plus the user pointer.
  type, extends(vci_model_t) :: c_model_t
    type(vci_callbacks_c) :: cb
    type(c_ptr) :: user = c_null_ptr
    integer :: refs = 0               !< the handle itself plus every integrator using the model
    integer(c_int) :: last_rc = 0     !< nonzero return of the last failing callback (0: none failed)
    character(len=24) :: last_failed = ''     !< which callback returned nonzero
    character(len=24) :: last_nonfinite = ''  !< which callback returned NaN/Inf (with 0)
  contains
    procedure :: d1 => cm_d1
    procedure :: d2 => cm_d2
    procedure :: d3 => cm_d3
    procedure :: mixed_hessian => cm_hessian
    procedure :: constraint_forms => cm_forms
    procedure :: discrete_constraint => cm_dconstraint
    procedure :: gaps => cm_gaps
    procedure :: gap_gradients => cm_gap_grads
    procedure :: energy => cm_energy
  end type c_model_t

  !> Forwards impacts to the C impact callback and everything to the output file, if any. The
  !> output sees one run from vci_open_output to vci_close_output/destroy, however many
  !> vci_step/vci_integrate calls it spans.
  type, extends(vci_observer_t) :: c_observer_t
    type(c_funptr) :: impact_fn = c_null_funptr
    type(c_ptr) :: user = c_null_ptr
    integer(c_int) :: impact_rc = 0
    real(dp) :: impact_t = 0.0_dp
    class(vci_observer_t), allocatable :: output
    logical :: started = .false.
  contains
    procedure :: on_start => obs_start
    procedure :: on_step => obs_step
    procedure :: on_impact => obs_impact
    procedure :: on_finish => obs_finish
  end type c_observer_t

  !> The object behind a `vci_integrator` handle.
  type :: c_integrator_t
    type(vci_integrator_t) :: integ
    type(c_model_t), pointer :: model => null()
    type(c_observer_t) :: obs
  end type c_integrator_t

  ! registry of live handles (addresses), so that no handle is dereferenced unless it is live
  integer, parameter :: KIND_MODEL = 1, KIND_INTEGRATOR = 2
  integer(c_intptr_t), allocatable, save :: live_addr(:)
  integer, allocatable, save :: live_kind(:)
  integer, save :: n_live = 0

  !> Message of the last failure not attached to a live integrator.
  character(len=VCI_MSG_LEN), save :: global_message = ''

  ! NUL-terminated status strings handed out by vci_status_string (static storage)
  integer, parameter :: STATUS_LEN = 48
  character(kind=c_char, len=STATUS_LEN), target, save :: status_text(0:11)
  logical, save :: status_text_ready = .false.

contains

  ! ---------------------------------------------------------------------------------------------
  ! registry

  integer(c_intptr_t) function addr_of(p)
    type(c_ptr), intent(in) :: p
    addr_of = transfer(p, 0_c_intptr_t)
  end function addr_of

  integer function find_live(p, kind)
    type(c_ptr), intent(in) :: p
    integer, intent(in) :: kind
    integer :: i
    integer(c_intptr_t) :: a
    find_live = 0
    if (.not. c_associated(p)) return
    a = addr_of(p)
    do i = 1, n_live
      if (live_addr(i) == a .and. live_kind(i) == kind) then
        find_live = i; return
      end if
    end do
  end function find_live

  subroutine register(p, kind)
    type(c_ptr), intent(in) :: p
    integer, intent(in) :: kind
    integer(c_intptr_t), allocatable :: ta(:)
    integer, allocatable :: tk(:)
    if (.not. allocated(live_addr)) allocate (live_addr(8), live_kind(8))
    if (n_live == size(live_addr)) then
      allocate (ta(2 * n_live), tk(2 * n_live))
      ta(1:n_live) = live_addr(1:n_live); tk(1:n_live) = live_kind(1:n_live)
      call move_alloc(ta, live_addr); call move_alloc(tk, live_kind)
    end if
    n_live = n_live + 1
    live_addr(n_live) = addr_of(p); live_kind(n_live) = kind
  end subroutine register

  subroutine unregister(i)
    integer, intent(in) :: i
    live_addr(i) = live_addr(n_live); live_kind(i) = live_kind(n_live)
    n_live = n_live - 1
    if (n_live == 0) deallocate (live_addr, live_kind)   ! nothing left behind at exit
  end subroutine unregister

  !> The model behind a live handle, or a status and a global message naming the caller.
  subroutine get_model(handle, who, mp, stat)
    type(c_ptr), intent(in) :: handle
    character(len=*), intent(in) :: who
    type(c_model_t), pointer, intent(out) :: mp
    integer, intent(out) :: stat
    mp => null()
    if (.not. c_associated(handle)) then
      global_message = who//': the model handle is NULL'
      stat = VCI_ERR_ARGUMENT; return
    end if
    if (find_live(handle, KIND_MODEL) == 0) then
      global_message = who//': not a live model handle (destroyed, or not made by vci_model_create)'
      stat = VCI_ERR_ARGUMENT; return
    end if
    call c_f_pointer(handle, mp)
    stat = VCI_OK
  end subroutine get_model

  !> The integrator behind a live handle, or a status and a global message naming the caller.
  subroutine get_integ(handle, who, ip, stat)
    type(c_ptr), intent(in) :: handle
    character(len=*), intent(in) :: who
    type(c_integrator_t), pointer, intent(out) :: ip
    integer, intent(out) :: stat
    ip => null()
    if (.not. c_associated(handle)) then
      global_message = who//': the integrator handle is NULL'
      stat = VCI_ERR_ARGUMENT; return
    end if
    if (find_live(handle, KIND_INTEGRATOR) == 0) then
      global_message = who//': not a live integrator handle (destroyed, or not made by vci_integrator_create)'
      stat = VCI_ERR_ARGUMENT; return
    end if
    call c_f_pointer(handle, ip)
    ip%model%last_rc = 0; ip%model%last_failed = ''; ip%model%last_nonfinite = ''
    stat = VCI_OK
  end subroutine get_integ

  !> Record a failure detected in this layer on the integrator (read back with vci_last_error).
  integer function fail(ip, status, message)
    type(c_integrator_t), intent(inout) :: ip
    integer, intent(in) :: status
    character(len=*), intent(in) :: message
    ip%integ%status = status
    ip%integ%message = message
    fail = status
  end function fail

  !> After a call into the integrator: name the C callback that failed and its return code. The
  !> Newton line search backtracks from trial points where a callback fails or gives NaN/Inf, so a
  !> callback that keeps failing ends as VCI_ERR_NEWTON ("no decrease"); the C contract promises
  !> VCI_ERR_CALLBACK (VCI_ERR_NONFINITE) for it, so such failures are reported as the callback's,
  !> with the Newton message kept. A failing impact callback is VCI_ERR_CALLBACK, not an output error.
  integer function after_call(ip, stat) result(status)
    type(c_integrator_t), intent(inout) :: ip
    integer, intent(in) :: stat
    character(len=32) :: rc
    status = stat
    if ((stat == VCI_ERR_CALLBACK .or. stat == VCI_ERR_NEWTON) .and. ip%model%last_rc /= 0) then
      write (rc, '(i0)') ip%model%last_rc
      ip%integ%message = trim(ip%integ%message)//' (the C callback '//trim(ip%model%last_failed)// &
                         ' returned '//trim(rc)//')'
      status = VCI_ERR_CALLBACK
    else if ((stat == VCI_ERR_NONFINITE .or. stat == VCI_ERR_NEWTON) .and. ip%model%last_nonfinite /= '') then
      ip%integ%message = trim(ip%integ%message)//' (the C callback '//trim(ip%model%last_nonfinite)// &
                         ' returned NaN or Inf)'
      status = VCI_ERR_NONFINITE
    else if (stat == VCI_ERR_IO .and. ip%obs%impact_rc /= 0) then
      write (rc, '(i0)') ip%obs%impact_rc
      write (ip%integ%message, '(a,es14.7,a)') 'impact callback returned '//trim(rc)//' at the impact at t = ', &
        ip%obs%impact_t, '; the step containing it was accepted, the state is after it'
      status = VCI_ERR_CALLBACK
    end if
    ip%integ%status = status
    ip%obs%impact_rc = 0
  end function after_call

  !> A C array of n doubles as a Fortran pointer; false (and a message) when NULL.
  logical function c_array(p, n, arr)
    type(c_ptr), intent(in) :: p
    integer, intent(in) :: n
    real(c_double), pointer, intent(out) :: arr(:)
    arr => null()
    c_array = c_associated(p)
    if (c_array) call c_f_pointer(p, arr, [n])
  end function c_array

  ! ---------------------------------------------------------------------------------------------
  ! the C model: each procedure presets nothing (stat arrives as 0) and maps any nonzero C return
  ! to 1, so that a C callback can never be mistaken for "not provided" (VCI_NOT_PROVIDED)

  !> Record a callback's outcome: nonzero rc becomes stat = 1; NaN/Inf outputs are remembered, so
  !> that a failure the Newton line search absorbed (it backtracks from failing trial points) can
  !> still be reported as the callback's (see after_call).
  subroutine note(self, rc, name, finite, stat)
    class(c_model_t), intent(inout) :: self
    integer(c_int), intent(in) :: rc
    character(len=*), intent(in) :: name
    logical, intent(in) :: finite
    integer, intent(inout) :: stat
    if (rc /= 0) then
      self%last_rc = rc
      self%last_failed = name
      stat = 1
    else if (.not. finite) then
      self%last_nonfinite = name
    end if
  end subroutine note

  subroutine cm_d1(self, q, v, h, out, stat)
    class(c_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    procedure(c_ld_grad_fn), pointer :: f
    call c_f_procpointer(self%cb%d1_ld, f)
    call note(self, f(self%n, q, v, h, out, self%user), 'd1_ld', all(ieee_is_finite(out)), stat)
  end subroutine cm_d1

  subroutine cm_d2(self, q, v, h, out, stat)
    class(c_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    procedure(c_ld_grad_fn), pointer :: f
    call c_f_procpointer(self%cb%d2_ld, f)
    call note(self, f(self%n, q, v, h, out, self%user), 'd2_ld', all(ieee_is_finite(out)), stat)
  end subroutine cm_d2

  subroutine cm_d3(self, q, v, h, out, stat)
    class(c_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: out
    integer, intent(inout) :: stat
    procedure(c_ld_grad_fn), pointer :: f
    real(c_double) :: tmp(1)
    tmp = 0.0_dp
    call c_f_procpointer(self%cb%d3_ld, f)
    call note(self, f(self%n, q, v, h, tmp, self%user), 'd3_ld', ieee_is_finite(tmp(1)), stat)
    out = tmp(1)
  end subroutine cm_d3

  subroutine cm_hessian(self, q, v, h, hess, stat)
    class(c_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), v(:), h
    real(dp), intent(out) :: hess(:, :)
    integer, intent(inout) :: stat
    procedure(c_ld_grad_fn), pointer :: f
    if (.not. c_associated(self%cb%mixed_hessian)) then
      hess = 0.0_dp; stat = VCI_NOT_PROVIDED; return
    end if
    call c_f_procpointer(self%cb%mixed_hessian, f)
    call note(self, f(self%n, q, v, h, hess, self%user), 'mixed_hessian', all(ieee_is_finite(hess)), stat)
  end subroutine cm_hessian

  subroutine cm_forms(self, q, omega, stat)
    class(c_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: omega(:, :)
    integer, intent(inout) :: stat
    procedure(c_forms_fn), pointer :: f
    if (.not. c_associated(self%cb%constraint_forms)) then
      omega = 0.0_dp; stat = VCI_NOT_PROVIDED; return
    end if
    call c_f_procpointer(self%cb%constraint_forms, f)
    call note(self, f(self%n, self%m, q, omega, self%user), 'constraint_forms', all(ieee_is_finite(omega)), stat)
  end subroutine cm_forms

  subroutine cm_dconstraint(self, base, other, h, out, stat)
    class(c_model_t), intent(inout) :: self
    real(dp), intent(in) :: base(:), other(:), h
    real(dp), intent(out) :: out(:)
    integer, intent(inout) :: stat
    procedure(c_dconstraint_fn), pointer :: f
    if (.not. c_associated(self%cb%discrete_constraint)) then
      out = 0.0_dp; stat = VCI_NOT_PROVIDED; return
    end if
    call c_f_procpointer(self%cb%discrete_constraint, f)
    call note(self, f(self%n, self%m, base, other, h, out, self%user), 'discrete_constraint', &
              all(ieee_is_finite(out)), stat)
  end subroutine cm_dconstraint

  subroutine cm_gaps(self, q, g, stat)
    class(c_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    procedure(c_forms_fn), pointer :: f
    if (.not. c_associated(self%cb%gaps)) then
      g = 0.0_dp; stat = VCI_NOT_PROVIDED; return
    end if
    call c_f_procpointer(self%cb%gaps, f)
    call note(self, f(self%n, self%n_gaps, q, g, self%user), 'gaps', all(ieee_is_finite(g)), stat)
  end subroutine cm_gaps

  subroutine cm_gap_grads(self, q, dg, stat)
    class(c_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    procedure(c_forms_fn), pointer :: f
    if (.not. c_associated(self%cb%gap_gradients)) then
      dg = 0.0_dp; stat = VCI_NOT_PROVIDED; return
    end if
    call c_f_procpointer(self%cb%gap_gradients, f)
    call note(self, f(self%n, self%n_gaps, q, dg, self%user), 'gap_gradients', all(ieee_is_finite(dg)), stat)
  end subroutine cm_gap_grads

  subroutine cm_energy(self, q, p, e, stat)
    class(c_model_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    procedure(c_energy_fn), pointer :: f
    real(c_double) :: tmp(1)
    if (.not. c_associated(self%cb%energy)) then
      e = 0.0_dp; stat = VCI_NOT_PROVIDED; return
    end if
    tmp = 0.0_dp
    call c_f_procpointer(self%cb%energy, f)
    call note(self, f(self%n, q, p, tmp, self%user), 'energy', ieee_is_finite(tmp(1)), stat)
    e = tmp(1)
  end subroutine cm_energy

  ! ---------------------------------------------------------------------------------------------
  ! the observer behind vci_set_impact_callback and vci_open_output

  subroutine obs_start(self, info, q, p, stat)
    class(c_observer_t), intent(inout) :: self
    type(vci_run_info_t), intent(in) :: info
    real(dp), intent(in) :: q(:), p(:)
    integer, intent(inout) :: stat
    if (.not. allocated(self%output) .or. self%started) return
    call self%output%on_start(info, q, p, stat)
    self%started = .true.
  end subroutine obs_start

  subroutine obs_step(self, step, t, q, p, lambda, energy, stat)
    class(c_observer_t), intent(inout) :: self
    integer(i8), intent(in) :: step
    real(dp), intent(in) :: t, q(:), p(:), lambda(:), energy
    integer, intent(inout) :: stat
    if (allocated(self%output)) call self%output%on_step(step, t, q, p, lambda, energy, stat)
  end subroutine obs_step

  subroutine obs_impact(self, impact, stat)
    class(c_observer_t), intent(inout) :: self
    type(vci_impact_t), intent(in) :: impact
    integer, intent(inout) :: stat
    procedure(c_impact_fn), pointer :: f
    integer(c_int) :: rc
    if (c_associated(self%impact_fn) .and. stat == 0) then
      call c_f_procpointer(self%impact_fn, f)
      ! C numbers the gaps from 0, as in the g[] array of vci_gaps_fn
      rc = f(impact%t, impact%alpha, int(impact%gap - 1, c_int), impact%q, impact%impulse, self%user)
      if (rc /= 0) then
        self%impact_rc = rc; self%impact_t = impact%t
        stat = 1; return
      end if
    end if
    if (allocated(self%output) .and. stat == 0) call self%output%on_impact(impact, stat)
  end subroutine obs_impact

  !> Runs end at vci_close_output or destroy, not at the end of each vci_integrate call.
  subroutine obs_finish(self, status, message, stat)
    class(c_observer_t), intent(inout) :: self
    integer, intent(in) :: status
    character(len=*), intent(in) :: message
    integer, intent(inout) :: stat
  end subroutine obs_finish

  !> Finish and drop the output of an integrator; the status of closing it.
  integer function close_output(ip) result(stat)
    type(c_integrator_t), intent(inout) :: ip
    stat = 0
    if (.not. allocated(ip%obs%output)) return
    ! also when no step was written: the writer then just closes its file
    call ip%obs%output%on_finish(ip%integ%status, trim(ip%integ%message), stat)
    deallocate (ip%obs%output)
    ip%obs%started = .false.
    if (stat /= 0) stat = VCI_ERR_IO
  end function close_output

  ! ---------------------------------------------------------------------------------------------
  ! the C entry points (vci.h documents each one's statuses)

  !> int vci_model_create(vci_model *model, int n, int m, int ngaps, const vci_callbacks *cb, void *user)
  integer(c_int) function vci_model_create(model, n, m, ngaps, cb, user) bind(C, name='vci_model_create')
    type(c_ptr), value :: model, cb, user
    integer(c_int), value :: n, m, ngaps
    type(c_ptr), pointer :: out
    type(vci_callbacks_c), pointer :: fcb
    type(c_model_t), pointer :: mp
    character(len=64) :: what
    character(len=:), allocatable :: why
    integer :: st
    vci_model_create = VCI_ERR_ARGUMENT
    if (.not. c_associated(model)) then
      global_message = 'vci_model_create: the model argument is NULL'; return
    end if
    call c_f_pointer(model, out)
    out = c_null_ptr
    why = vci_size_problem(int(n), int(m), int(ngaps))
    if (why /= '') then
      write (global_message, '(a,3(i0,a))') 'vci_model_create: sizes n = ', n, ', m = ', m, ', ngaps = ', ngaps, &
        ' invalid ('//why//')'
      return
    end if
    if (.not. c_associated(cb)) then
      global_message = 'vci_model_create: the callbacks argument is NULL'; return
    end if
    call c_f_pointer(cb, fcb)
    what = ''
    if (.not. c_associated(fcb%d1_ld)) what = 'd1_ld'
    if (.not. c_associated(fcb%d2_ld)) what = 'd2_ld'
    if (.not. c_associated(fcb%d3_ld)) what = 'd3_ld'
    if (m > 0 .and. .not. c_associated(fcb%constraint_forms)) what = 'constraint_forms (needed as m > 0)'
    if (m > 0 .and. .not. c_associated(fcb%discrete_constraint)) what = 'discrete_constraint (needed as m > 0)'
    if (ngaps > 0 .and. .not. c_associated(fcb%gaps)) what = 'gaps (needed as ngaps > 0)'
    if (what /= '') then
      global_message = 'vci_model_create: callback '//trim(what)//' is NULL'; return
    end if
    allocate (mp, stat=st)
    if (st /= 0) then
      global_message = 'vci_model_create: out of memory'
      vci_model_create = VCI_ERR_MEMORY; return
    end if
    mp%n = n; mp%m = m; mp%n_gaps = ngaps
    mp%cb = fcb
    mp%user = user
    mp%refs = 1
    out = c_loc(mp)
    call register(out, KIND_MODEL)
    vci_model_create = VCI_OK
  end function vci_model_create

  !> Drop one reference to a model; free it when no integrator uses it any more.
  subroutine release_model(mp)
    type(c_model_t), pointer, intent(inout) :: mp
    mp%refs = mp%refs - 1
    if (mp%refs <= 0) deallocate (mp)
    mp => null()
  end subroutine release_model

  !> void vci_model_destroy(vci_model *model): NULL-safe, sets *model = NULL.
  subroutine vci_model_destroy(model) bind(C, name='vci_model_destroy')
    type(c_ptr), value :: model
    type(c_ptr), pointer :: h
    type(c_model_t), pointer :: mp
    integer :: i
    if (.not. c_associated(model)) return
    call c_f_pointer(model, h)
    if (.not. c_associated(h)) return
    i = find_live(h, KIND_MODEL)
    if (i == 0) then
      global_message = 'vci_model_destroy: not a live model handle (destroyed twice?); ignored'
    else
      call unregister(i)
      call c_f_pointer(h, mp)
      call release_model(mp)
    end if
    h = c_null_ptr
  end subroutine vci_model_destroy

  !> int vci_integrator_create(vci_integrator *integ, vci_model model, double h)
  integer(c_int) function vci_integrator_create(integ, model, h) bind(C, name='vci_integrator_create')
    type(c_ptr), value :: integ, model
    real(c_double), value :: h
    type(c_ptr), pointer :: out
    type(c_model_t), pointer :: mp
    type(c_integrator_t), pointer :: ip
    integer :: stat
    if (.not. c_associated(integ)) then
      global_message = 'vci_integrator_create: the integ argument is NULL'
      vci_integrator_create = VCI_ERR_ARGUMENT; return
    end if
    call c_f_pointer(integ, out)
    out = c_null_ptr
    call get_model(model, 'vci_integrator_create', mp, stat)
    if (stat /= VCI_OK) then
      vci_integrator_create = stat; return
    end if
    allocate (ip, stat=stat)
    if (stat /= 0) then
      global_message = 'vci_integrator_create: out of memory'
      vci_integrator_create = VCI_ERR_MEMORY; return
    end if
    call ip%integ%create(mp, real(h, dp), stat)
    if (stat /= VCI_OK) then
      global_message = 'vci_integrator_create: '//trim(ip%integ%message)
      deallocate (ip)
      vci_integrator_create = stat; return
    end if
    ! defined values before any init: set_impact_energy probes the energy callback at (q, p)
    ip%integ%q = 0.0_dp; ip%integ%p = 0.0_dp
    ip%model => mp
    mp%refs = mp%refs + 1
    out = c_loc(ip)
    call register(out, KIND_INTEGRATOR)
    vci_integrator_create = VCI_OK
  end function vci_integrator_create

  !> void vci_integrator_destroy(vci_integrator *integ): NULL-safe, sets *integ = NULL; closes output.
  subroutine vci_integrator_destroy(integ) bind(C, name='vci_integrator_destroy')
    type(c_ptr), value :: integ
    type(c_ptr), pointer :: h
    type(c_integrator_t), pointer :: ip
    integer :: i, stat
    if (.not. c_associated(integ)) return
    call c_f_pointer(integ, h)
    if (.not. c_associated(h)) return
    i = find_live(h, KIND_INTEGRATOR)
    if (i == 0) then
      global_message = 'vci_integrator_destroy: not a live integrator handle (destroyed twice?); ignored'
    else
      call unregister(i)
      call c_f_pointer(h, ip)
      stat = close_output(ip)
      if (stat /= VCI_OK) global_message = 'vci_integrator_destroy: the output file could not be finished'
      call release_model(ip%model)
      deallocate (ip)
    end if
    h = c_null_ptr
  end subroutine vci_integrator_destroy

  !> int vci_set_tolerances(vci_integrator integ, double atol, double rtol, int max_iterations)
  integer(c_int) function vci_set_tolerances(integ, atol, rtol, max_iterations) bind(C, name='vci_set_tolerances')
    type(c_ptr), value :: integ
    real(c_double), value :: atol, rtol
    integer(c_int), value :: max_iterations
    type(c_integrator_t), pointer :: ip
    integer :: stat
    call get_integ(integ, 'vci_set_tolerances', ip, stat)
    if (stat == VCI_OK) call ip%integ%set_tolerances(real(atol, dp), real(rtol, dp), int(max_iterations), stat)
    vci_set_tolerances = stat
  end function vci_set_tolerances

  !> int vci_set_impact_energy(vci_integrator integ, int mode): 0 discrete (default), 1 hamiltonian.
  integer(c_int) function vci_set_impact_energy(integ, mode) bind(C, name='vci_set_impact_energy')
    type(c_ptr), value :: integ
    integer(c_int), value :: mode
    type(c_integrator_t), pointer :: ip
    integer :: stat
    call get_integ(integ, 'vci_set_impact_energy', ip, stat)
    if (stat == VCI_OK) call ip%integ%set_impact_energy(int(mode), stat)
    vci_set_impact_energy = stat
  end function vci_set_impact_energy

  !> int vci_set_max_impacts(vci_integrator integ, int max_impacts): impacts allowed in one step.
  integer(c_int) function vci_set_max_impacts(integ, max_impacts) bind(C, name='vci_set_max_impacts')
    type(c_ptr), value :: integ
    integer(c_int), value :: max_impacts
    type(c_integrator_t), pointer :: ip
    integer :: stat
    call get_integ(integ, 'vci_set_max_impacts', ip, stat)
    if (stat == VCI_OK) call ip%integ%set_max_impacts(int(max_impacts), stat)
    vci_set_max_impacts = stat
  end function vci_set_max_impacts

  !> int vci_init_from_pair(vci_integrator integ, double t0, const double *q0, const double *q1)
  integer(c_int) function vci_init_from_pair(integ, t0, q0, q1) bind(C, name='vci_init_from_pair')
    type(c_ptr), value :: integ, q0, q1
    real(c_double), value :: t0
    type(c_integrator_t), pointer :: ip
    real(c_double), pointer :: a(:), b(:)
    integer :: stat
    call get_integ(integ, 'vci_init_from_pair', ip, stat)
    if (stat /= VCI_OK) then
      vci_init_from_pair = stat; return
    end if
    if (.not. (c_array(q0, ip%model%n, a) .and. c_array(q1, ip%model%n, b))) then
      ip%integ%initialized = .false.
      vci_init_from_pair = fail(ip, VCI_ERR_ARGUMENT, 'vci_init_from_pair: q0 or q1 is NULL'); return
    end if
    call ip%integ%init_from_pair(real(t0, dp), a, b, stat)
    vci_init_from_pair = after_call(ip, stat)
  end function vci_init_from_pair

  !> int vci_init_from_momentum(vci_integrator integ, double t0, const double *q0, const double *p0)
  integer(c_int) function vci_init_from_momentum(integ, t0, q0, p0) bind(C, name='vci_init_from_momentum')
    type(c_ptr), value :: integ, q0, p0
    real(c_double), value :: t0
    type(c_integrator_t), pointer :: ip
    real(c_double), pointer :: a(:), b(:)
    integer :: stat
    call get_integ(integ, 'vci_init_from_momentum', ip, stat)
    if (stat /= VCI_OK) then
      vci_init_from_momentum = stat; return
    end if
    if (.not. (c_array(q0, ip%model%n, a) .and. c_array(p0, ip%model%n, b))) then
      ip%integ%initialized = .false.
      vci_init_from_momentum = fail(ip, VCI_ERR_ARGUMENT, 'vci_init_from_momentum: q0 or p0 is NULL'); return
    end if
    call ip%integ%init_from_momentum(real(t0, dp), a, b, stat)
    vci_init_from_momentum = after_call(ip, stat)
  end function vci_init_from_momentum

  !> int vci_step(vci_integrator integ, int direction)
  integer(c_int) function vci_step(integ, direction) bind(C, name='vci_step')
    type(c_ptr), value :: integ
    integer(c_int), value :: direction
    type(c_integrator_t), pointer :: ip
    integer :: stat, ostat
    call get_integ(integ, 'vci_step', ip, stat)
    if (stat /= VCI_OK) then
      vci_step = stat; return
    end if
    ! a single step has no on_start of its own: the output's run starts with the first step
    if (allocated(ip%obs%output) .and. .not. ip%obs%started .and. ip%integ%initialized .and. abs(direction) == 1) then
      ostat = 0
      call ip%obs%on_start(ip%integ%run_info(int(direction)), ip%integ%q, ip%integ%p, ostat)
      if (ostat /= 0) then
        vci_step = fail(ip, VCI_ERR_IO, 'vci_step: the output could not start the run'); return
      end if
    end if
    call ip%integ%step(int(direction), stat, ip%obs)
    vci_step = after_call(ip, stat)
  end function vci_step

  !> int vci_integrate(vci_integrator integ, long nsteps, int direction)
  integer(c_int) function vci_integrate(integ, nsteps, direction) bind(C, name='vci_integrate')
    type(c_ptr), value :: integ
    integer(c_long), value :: nsteps
    integer(c_int), value :: direction
    type(c_integrator_t), pointer :: ip
    integer :: stat
    call get_integ(integ, 'vci_integrate', ip, stat)
    if (stat /= VCI_OK) then
      vci_integrate = stat; return
    end if
    call ip%integ%integrate(int(nsteps, i8), int(direction), stat, ip%obs)
    vci_integrate = after_call(ip, stat)
  end function vci_integrate

  !> Common checks of the getters: a live, initialised integrator.
  subroutine get_ready(integ, who, ip, stat)
    type(c_ptr), intent(in) :: integ
    character(len=*), intent(in) :: who
    type(c_integrator_t), pointer, intent(out) :: ip
    integer, intent(out) :: stat
    call get_integ(integ, who, ip, stat)
    if (stat /= VCI_OK) return
    if (.not. ip%integ%initialized) stat = fail(ip, VCI_ERR_STATE, who//': the integrator has no state yet '// &
                                                '(call vci_init_from_pair or vci_init_from_momentum)')
  end subroutine get_ready

  !> int vci_get_state(vci_integrator integ, double *t, double *q, double *p): NULL outputs are skipped.
  integer(c_int) function vci_get_state(integ, t, q, p) bind(C, name='vci_get_state')
    type(c_ptr), value :: integ, t, q, p
    type(c_integrator_t), pointer :: ip
    real(c_double), pointer :: tt, a(:)
    integer :: stat
    call get_ready(integ, 'vci_get_state', ip, stat)
    vci_get_state = stat
    if (stat /= VCI_OK) return
    if (c_associated(t)) then
      call c_f_pointer(t, tt); tt = ip%integ%t
    end if
    if (c_array(q, ip%model%n, a)) a = ip%integ%q
    if (c_array(p, ip%model%n, a)) a = ip%integ%p
  end function vci_get_state

  !> int vci_get_multipliers(vci_integrator integ, double *lambda /* [m] */)
  integer(c_int) function vci_get_multipliers(integ, lambda) bind(C, name='vci_get_multipliers')
    type(c_ptr), value :: integ, lambda
    type(c_integrator_t), pointer :: ip
    real(c_double), pointer :: a(:)
    integer :: stat
    call get_ready(integ, 'vci_get_multipliers', ip, stat)
    vci_get_multipliers = stat
    if (stat /= VCI_OK) return          ! (Fortran does not short-circuit: ip may be null)
    if (ip%model%m == 0) return
    if (.not. c_array(lambda, ip%model%m, a)) then
      vci_get_multipliers = fail(ip, VCI_ERR_ARGUMENT, 'vci_get_multipliers: lambda is NULL'); return
    end if
    a = ip%integ%lambda
  end function vci_get_multipliers

  !> int vci_get_energy(vci_integrator integ, double *energy): E_d of the last step.
  integer(c_int) function vci_get_energy(integ, energy) bind(C, name='vci_get_energy')
    type(c_ptr), value :: integ, energy
    type(c_integrator_t), pointer :: ip
    real(c_double), pointer :: e
    integer :: stat
    call get_ready(integ, 'vci_get_energy', ip, stat)
    vci_get_energy = stat
    if (stat /= VCI_OK) return
    if (.not. c_associated(energy)) then
      vci_get_energy = fail(ip, VCI_ERR_ARGUMENT, 'vci_get_energy: energy is NULL'); return
    end if
    call c_f_pointer(energy, e)
    e = ip%integ%energy
  end function vci_get_energy

  !> int vci_get_index(vci_integrator integ, long *k): index of the current state (t = t0 + k h).
  integer(c_int) function vci_get_index(integ, k) bind(C, name='vci_get_index')
    type(c_ptr), value :: integ, k
    type(c_integrator_t), pointer :: ip
    integer(c_long), pointer :: kk
    integer :: stat
    call get_ready(integ, 'vci_get_index', ip, stat)
    vci_get_index = stat
    if (stat /= VCI_OK) return
    if (.not. c_associated(k)) then
      vci_get_index = fail(ip, VCI_ERR_ARGUMENT, 'vci_get_index: k is NULL'); return
    end if
    call c_f_pointer(k, kk)
    kk = int(ip%integ%k, c_long)
  end function vci_get_index

  !> int vci_get_stats(vci_integrator integ, long *steps, long *impacts, long *newton_iterations)
  integer(c_int) function vci_get_stats(integ, steps, impacts, newton_iterations) bind(C, name='vci_get_stats')
    type(c_ptr), value :: integ, steps, impacts, newton_iterations
    type(c_integrator_t), pointer :: ip
    integer :: stat
    call get_integ(integ, 'vci_get_stats', ip, stat)
    vci_get_stats = stat
    if (stat /= VCI_OK) return
    call put_long(steps, ip%integ%stats%steps)
    call put_long(impacts, ip%integ%stats%impacts)
    call put_long(newton_iterations, ip%integ%stats%newton_iterations)
  contains
    subroutine put_long(p, v)
      type(c_ptr), intent(in) :: p
      integer(i8), intent(in) :: v
      integer(c_long), pointer :: l
      if (.not. c_associated(p)) return
      call c_f_pointer(p, l)
      l = int(v, c_long)
    end subroutine put_long
  end function vci_get_stats

  !> int vci_set_impact_callback(vci_integrator integ, vci_impact_fn fn, void *user): NULL fn removes it.
  integer(c_int) function vci_set_impact_callback(integ, fn, user) bind(C, name='vci_set_impact_callback')
    type(c_ptr), value :: integ, user
    type(c_funptr), value :: fn
    type(c_integrator_t), pointer :: ip
    integer :: stat
    call get_integ(integ, 'vci_set_impact_callback', ip, stat)
    vci_set_impact_callback = stat
    if (stat /= VCI_OK) return
    ip%obs%impact_fn = fn
    ip%obs%user = user
  end function vci_set_impact_callback

  !> int vci_open_output(vci_integrator integ, const char *path): HDF5 trajectory file (replaced if
  !> it exists); VCI_ERR_IO when the library was built without HDF5.
  integer(c_int) function vci_open_output(integ, path) bind(C, name='vci_open_output')
    type(c_ptr), value :: integ, path
    type(c_integrator_t), pointer :: ip
    character(kind=c_char), pointer :: chars(:)
    character(len=:), allocatable :: fpath
    integer :: stat, i, nc
    call get_integ(integ, 'vci_open_output', ip, stat)
    if (stat /= VCI_OK) then
      vci_open_output = stat; return
    end if
    if (.not. c_associated(path)) then
      vci_open_output = fail(ip, VCI_ERR_ARGUMENT, 'vci_open_output: path is NULL'); return
    end if
    nc = int(c_strlen(path))
    if (nc == 0) then
      vci_open_output = fail(ip, VCI_ERR_ARGUMENT, 'vci_open_output: path is empty'); return
    end if
    call c_f_pointer(path, chars, [nc])
    allocate (character(len=nc) :: fpath)
    do i = 1, nc
      fpath(i:i) = chars(i)
    end do
    stat = close_output(ip)
    if (stat /= VCI_OK) then
      vci_open_output = fail(ip, stat, 'vci_open_output: the previous output file could not be finished'); return
    end if
#ifdef VCI_HAVE_HDF5
    block
      type(vci_hdf5_writer_t), allocatable :: w
      allocate (w)
      call w%open(fpath, stat, overwrite=.true.)
      if (stat /= VCI_OK) then
        vci_open_output = fail(ip, VCI_ERR_IO, 'vci_open_output: '//trim(w%message)); return
      end if
      call w%attach(ip%integ)   ! checkpoints in the file: restarts continue bit for bit
      call move_alloc(w, ip%obs%output)
    end block
    ip%obs%started = .false.
    ip%integ%status = VCI_OK; ip%integ%message = ''
    vci_open_output = VCI_OK
#else
    vci_open_output = fail(ip, VCI_ERR_IO, 'vci_open_output: cannot write '//fpath// &
                           ': this vci library was built without HDF5 (configure with -DVCI_WITH_HDF5=ON)')
#endif
  end function vci_open_output

  !> int vci_close_output(vci_integrator integ): finish and close the output file (no-op without one).
  integer(c_int) function vci_close_output(integ) bind(C, name='vci_close_output')
    type(c_ptr), value :: integ
    type(c_integrator_t), pointer :: ip
    integer :: stat
    call get_integ(integ, 'vci_close_output', ip, stat)
    if (stat == VCI_OK) then
      stat = close_output(ip)
      if (stat /= VCI_OK) stat = fail(ip, stat, 'vci_close_output: the output file could not be finished')
    end if
    vci_close_output = stat
  end function vci_close_output

  !> int vci_last_error(vci_integrator integ, char *buffer, int size): the message of the last
  !> call on integ (empty after success), or with integ == NULL the last failure that had no live
  !> integrator to hold it. Truncated to size - 1 characters and NUL-terminated.
  integer(c_int) function vci_last_error(integ, buffer, size) bind(C, name='vci_last_error')
    type(c_ptr), value :: integ, buffer
    integer(c_int), value :: size
    character(kind=c_char), pointer :: out(:)
    character(len=VCI_MSG_LEN) :: msg
    type(c_integrator_t), pointer :: ip
    integer :: i, nc
    if (.not. c_associated(buffer) .or. size < 1) then
      vci_last_error = VCI_ERR_ARGUMENT; return
    end if
    vci_last_error = VCI_OK
    if (.not. c_associated(integ)) then
      msg = global_message
    else if (find_live(integ, KIND_INTEGRATOR) == 0) then
      msg = 'vci_last_error: not a live integrator handle (destroyed, or not made by vci_integrator_create)'
      vci_last_error = VCI_ERR_ARGUMENT
    else
      call c_f_pointer(integ, ip)
      msg = ip%integ%message
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
    if (.not. status_text_ready) then
      do i = lbound(status_text, 1), ubound(status_text, 1)
        status_text(i) = vci_status_name(i)//c_null_char
      end do
      status_text_ready = .true.
    end if
    i = ubound(status_text, 1)    ! 'unknown status'
    if (status >= VCI_OK .and. status < ubound(status_text, 1)) i = int(status)
    vci_status_string = c_loc(status_text(i))
  end function vci_status_string

  !> int vci_version(void): major*10000 + minor*100 + patch.
  integer(c_int) function vci_version() bind(C, name='vci_version')
    vci_version = VCI_VERSION_NUMBER
  end function vci_version
end module vci_capi
