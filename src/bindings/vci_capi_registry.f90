!> The handles of the C ABI (include/vci.h) and the objects behind them.
!>
!> Handles are not addresses: a handle is a token (serial number, slot) into a registry of live
!> objects. Serial numbers are never reused, so NULL, destroyed, foreign or garbage handles give
!> VCI_ERR_ARGUMENT instead of a crash even after malloc has reused the memory of a destroyed object.
!> The registry is guarded by a lock (vci_capi_sync.c), so handles may be created, used and
!> destroyed from any thread.
!>
!> No mutable state is shared between integrators: a model is immutable once created, and each
!> integrator keeps its own copy of it (callbacks, user pointer, sizes) together with its own
!> status, message and callback record. An integrator is marked busy while a call on it runs
!> (enter / leave); another call on it (from a callback it is running, or from another thread)
!> gives VCI_ERR_STATE, and vci_integrator_destroy of a busy integrator is carried out when the
!> running call returns. Failures without a live integrator to hold them (bad handles, failed
!> creation) go to a message of the calling thread. HDF5 is not thread-safe: all output calls are
!> serialised by a second lock. Also here: the observer behind vci_set_impact_callback and
!> vci_open_output. Internal to the bindings: public for vci_capi only.
module vci_capi_registry
  use, intrinsic :: iso_c_binding
  use vci_kinds, only: dp, i8
  use vci_status
  use vci_observer, only: vci_observer_t, vci_run_info_t, vci_impact_t
  use vci_checkpoint, only: vci_checkpoint_t
  use vci_progress, only: vci_progress_t, vci_progress_info_t
  use vci_integrator, only: vci_integrator_t
  use vci_capi_models, only: c_model_t, c_lagrangian_t, c_separable_t, c_impact_fn
  implicit none
  public

  ! src/bindings/vci_capi_sync.c
  interface
    pure integer(c_size_t) function c_strlen(s) bind(C, name='strlen')
      import :: c_size_t, c_ptr
      type(c_ptr), value, intent(in) :: s
    end function c_strlen
    subroutine lock_registry() bind(C, name='vci_lock_registry')
    end subroutine lock_registry
    subroutine unlock_registry() bind(C, name='vci_unlock_registry')
    end subroutine unlock_registry
    subroutine lock_io() bind(C, name='vci_lock_io')
    end subroutine lock_io
    subroutine unlock_io() bind(C, name='vci_unlock_io')
    end subroutine unlock_io
    subroutine c_set_thread_message(msg, len) bind(C, name='vci_set_thread_message')
      import :: c_char, c_int
      character(kind=c_char), intent(in) :: msg(*)
      integer(c_int), value :: len
    end subroutine c_set_thread_message
    integer(c_int) function c_get_thread_message(buf, size) bind(C, name='vci_get_thread_message')
      import :: c_char, c_int
      character(kind=c_char), intent(inout) :: buf(*)
      integer(c_int), value :: size
    end function c_get_thread_message
  end interface

  !> Forwards impacts to the C impact callback and everything to the output file, if any. The
  !> output sees one run from vci_open_output to vci_close_output/destroy, however many
  !> vci_step/vci_integrate calls it spans (all in one direction, from one initialisation).
  type, extends(vci_observer_t) :: c_observer_t
    type(c_funptr) :: impact_fn = c_null_funptr
    type(c_ptr) :: user = c_null_ptr
    integer(c_int) :: impact_rc = 0
    real(dp) :: impact_t = 0.0_dp
    class(vci_observer_t), allocatable :: output
    logical :: started = .false.
    integer :: direction = 0               !< of the output's run, once started
    type(c_integrator_t), pointer :: owner => null()
    logical :: stopped_by_destroy = .false.
    !> the run's end the output records: the last vci_step/vci_integrate on it (note_run_end), not
    !> the call that closes it (whose own status is 0 by then, or a refused getter's)
    integer :: run_status = 0
    character(len=VCI_MSG_LEN) :: run_message = ''
  contains

    procedure :: on_start => obs_start
    procedure :: on_step => obs_step
    procedure :: on_impact => obs_impact
    procedure :: on_split => obs_split
    procedure :: on_finish => obs_finish
    procedure :: keeps_checkpoints => obs_keeps_checkpoints
    procedure :: wants_checkpoint => obs_wants_checkpoint
    procedure :: on_checkpoint => obs_checkpoint
    procedure :: failure_cause => obs_failure_cause
  end type c_observer_t

  !> The C struct vci_progress.
  type, bind(C) :: vci_progress_c
    integer(c_int64_t) :: steps_done, steps_total, impacts
    real(c_double) :: t, elapsed, steps_per_second, eta
  end type vci_progress_c

  !> A C progress callback (vci_set_progress) as the integrator's progress object.
  type, extends(vci_progress_t) :: c_progress_t
    type(c_funptr) :: fn = c_null_funptr
    type(c_ptr) :: user = c_null_ptr
  contains
    procedure :: report => c_progress_report
  end type c_progress_t

  abstract interface
    integer(c_int) function c_progress_fn(info, user) bind(C)
      import :: vci_progress_c, c_int, c_ptr
      type(vci_progress_c), intent(in) :: info
      type(c_ptr), value :: user
    end function c_progress_fn
  end interface

  type :: c_integrator_t
    type(vci_integrator_t) :: integ
    type(c_progress_t) :: progress        !< vci_set_progress's callback
    type(c_model_t) :: model              !< this integrator's own copy of the model (and its record)
    type(c_lagrangian_t) :: lag           !< the continuous model it drives, when model%continuous
    type(c_separable_t) :: sep            !< the separable model it drives, when model%separable
    type(c_observer_t) :: obs
    logical :: busy = .false.             !< a call on it is running (guarded by the registry lock)
    logical :: destroy_pending = .false.  !< destroyed while busy: freed when that call returns
  end type c_integrator_t

  ! The registry: a handle is the token serial * 2**slot_bits + slot; slot 0 is never used, so no
  ! handle is NULL. Serial numbers grow by one per created object and are never reused.
  integer, parameter :: KIND_MODEL = 1, KIND_INTEGRATOR = 2
  integer, parameter :: slot_bits = merge(20, 12, bit_size(0_c_intptr_t) > 32)
  integer(c_intptr_t), parameter :: slot_mask = 2_c_intptr_t**slot_bits - 1
  ! huge / 2**slot_bits, as a shift (a constant integer division draws -Winteger-division)
  integer(c_intptr_t), parameter :: max_serial = shiftr(huge(0_c_intptr_t), slot_bits)
  type :: slot_t
    integer(c_intptr_t) :: serial = 0      !< 0: free
    integer :: kind = 0
    type(c_model_t), pointer :: model => null()
    type(c_integrator_t), pointer :: integ => null()
  end type slot_t
  type(slot_t), allocatable, save :: slots(:)
  integer, save :: n_live = 0
  integer(c_intptr_t), save :: last_serial = 0

contains

  subroutine c_progress_report(self, info, stop_requested)
    class(c_progress_t), intent(inout) :: self
    type(vci_progress_info_t), intent(in) :: info
    logical, intent(inout) :: stop_requested
    procedure(c_progress_fn), pointer :: f
    type(vci_progress_c) :: ci
    if (.not. c_associated(self%fn)) return
    ci = vci_progress_c(info%steps_done, info%steps_total, info%impacts, info%t, info%elapsed, &
                        info%steps_per_second, info%eta)
    call c_f_procpointer(self%fn, f)
    stop_requested = f(ci, self%user) /= 0
  end subroutine c_progress_report

  ! ---------------------------------------------------------------------------------------------
  ! the calling thread's message (failures without a live integrator)

  subroutine set_thread_message(msg)
    character(len=*), intent(in) :: msg
    character(kind=c_char) :: buf(max(1, len_trim(msg)))
    integer :: i
    do i = 1, len_trim(msg)
      buf(i) = msg(i:i)
    end do
    call c_set_thread_message(buf, int(len_trim(msg), c_int))
  end subroutine set_thread_message

  function thread_message() result(msg)
    character(len=VCI_MSG_LEN) :: msg
    character(kind=c_char) :: buf(VCI_MSG_LEN)
    integer :: i, n
    n = c_get_thread_message(buf, int(VCI_MSG_LEN, c_int))
    msg = ''
    do i = 1, n
      msg(i:i) = buf(i)
    end do
  end function thread_message

  ! ---------------------------------------------------------------------------------------------
  ! the registry (every procedure here runs with the registry lock held)

  !> The slot a handle names if it is live and of the given kind, else 0.
  integer function find_live(handle, kind) result(i)
    type(c_ptr), intent(in) :: handle
    integer, intent(in) :: kind
    integer(c_intptr_t) :: token, slot
    i = 0
    if (.not. c_associated(handle) .or. .not. allocated(slots)) return
    token = transfer(handle, token)
    if (token <= 0) return
    slot = iand(token, slot_mask)
    if (slot < 1 .or. slot > size(slots)) return
    if (slots(slot)%serial /= shiftr(token, slot_bits) .or. slots(slot)%kind /= kind) return
    i = int(slot)
  end function find_live

  !> Take a free slot for a new object; its handle, or C NULL when the registry is full.
  function register(kind, mp, ip) result(handle)
    integer, intent(in) :: kind
    type(c_model_t), pointer, intent(in) :: mp
    type(c_integrator_t), pointer, intent(in) :: ip
    type(c_ptr) :: handle
    type(slot_t), allocatable :: grown(:)
    integer :: i, st
    handle = c_null_ptr
    if (.not. allocated(slots)) then
      allocate (slots(16), stat=st)
      if (st /= 0) return
    end if
    i = 0
    if (n_live < size(slots)) then
      do i = 1, size(slots)
        if (slots(i)%serial == 0) exit
      end do
    end if
    if (i < 1 .or. i > size(slots)) then
      if (2_c_intptr_t * size(slots) > slot_mask) return      ! 2**slot_bits - 1 live handles at most
      allocate (grown(2 * size(slots)), stat=st)
      if (st /= 0) return
      grown(1:size(slots)) = slots
      i = size(slots) + 1
      call move_alloc(grown, slots)
    end if
    last_serial = last_serial + 1
    if (last_serial > max_serial) last_serial = 1             ! after ~8.8e12 handles (64-bit)
    slots(i)%serial = last_serial
    slots(i)%kind = kind
    slots(i)%model => mp
    slots(i)%integ => ip
    n_live = n_live + 1
    handle = transfer(last_serial * 2_c_intptr_t**slot_bits + i, handle)
  end function register

  subroutine unregister(i)
    integer, intent(in) :: i
    slots(i) = slot_t()
    n_live = n_live - 1
    if (n_live == 0) deallocate (slots)   ! nothing left behind at exit
  end subroutine unregister

  ! ---------------------------------------------------------------------------------------------
  ! entering and leaving a call on an integrator

  !> Look the handle up and mark the integrator busy; on failure a status and the thread's message.
  !> Every successful enter is paired with one leave. The call starts with a clean slate: status
  !> OK, empty message, empty callback record.
  subroutine enter(handle, who, ip, stat)
    type(c_ptr), intent(in) :: handle
    character(len=*), intent(in) :: who
    type(c_integrator_t), pointer, intent(out) :: ip
    integer, intent(out) :: stat
    integer :: i
    ip => null()
    stat = VCI_OK
    call lock_registry()
    i = find_live(handle, KIND_INTEGRATOR)
    if (i > 0) then
      ip => slots(i)%integ
      if (ip%busy) then
        ip => null()
        stat = VCI_ERR_STATE
      else
        ip%busy = .true.
      end if
    end if
    call unlock_registry()
    if (.not. c_associated(handle)) then
      call set_thread_message(who//': the integrator handle is NULL')
      stat = VCI_ERR_ARGUMENT
    else if (stat == VCI_ERR_STATE) then
      call set_thread_message(who//': the integrator is busy: a call on it is running (it may not be '// &
                              'called from its own callbacks, nor from two threads at once)')
    else if (i == 0) then
      call set_thread_message(who//': not a live integrator handle (destroyed, or not made by '// &
                              'vci_integrator_create)')
      stat = VCI_ERR_ARGUMENT
    else
      call ip%integ%report_failure(VCI_OK, '')
      call ip%model%record%clear()
    end if
  end subroutine enter

  !> The call on ip is over: not busy any more, and freed if it was destroyed meanwhile.
  subroutine leave(ip)
    type(c_integrator_t), pointer, intent(inout) :: ip
    logical :: free_it
    call lock_registry()
    ip%busy = .false.
    free_it = ip%destroy_pending
    call unlock_registry()
    if (free_it) call free_integrator(ip)
    ip => null()
  end subroutine leave

  !> Record a failure detected in this layer on the integrator (read back with vci_last_error).
  integer function fail(ip, status, message)
    type(c_integrator_t), intent(inout) :: ip
    integer, intent(in) :: status
    character(len=*), intent(in) :: message
    call ip%integ%report_failure(status, message)
    fail = status
  end function fail

  !> After a call into the integrator: name the C callback behind a callback failure (its code),
  !> and report a failing impact callback as VCI_ERR_CALLBACK, not as an output error. The status
  !> of the call itself; the integrator's status and message follow it.
  integer function after_call(ip, stat) result(status)
    type(c_integrator_t), intent(inout) :: ip
    integer, intent(in) :: stat
    character(len=32) :: rc
    character(len=VCI_MSG_LEN) :: msg
    status = stat
    msg = ip%integ%message_text()
    if (ip%obs%stopped_by_destroy) then
      status = VCI_ERR_STATE
      call set_thread_message('the integrator was destroyed during the call (from a callback or another '// &
                              'thread); the run stopped after the step under way')
    else if (stat == VCI_ERR_IO .and. ip%obs%impact_rc /= 0) then
      write (rc, '(i0)') ip%obs%impact_rc
      write (msg, '(a,es14.7,a)') 'impact callback returned '//trim(rc)//' at the impact at t = ', &
        ip%obs%impact_t, '; the step containing it was accepted, the state is after it'
      status = VCI_ERR_CALLBACK
    else
      call ip%model%record%annotate(stat, msg)
    end if
    call ip%integ%report_failure(status, msg)
    ip%obs%impact_rc = 0
  end function after_call

  !> A C array of n doubles as a Fortran pointer; false when NULL.
  logical function c_array(p, n, arr)
    type(c_ptr), intent(in) :: p
    integer, intent(in) :: n
    real(c_double), pointer, intent(out) :: arr(:)
    arr => null()
    c_array = c_associated(p)
    if (c_array) call c_f_pointer(p, arr, [n])
  end function c_array

  ! ---------------------------------------------------------------------------------------------
  ! the observer behind vci_set_impact_callback and vci_open_output

  subroutine obs_start(self, info, q, p, stat)
    class(c_observer_t), intent(inout) :: self
    type(vci_run_info_t), intent(in) :: info
    real(dp), intent(in) :: q(:), p(:)
    integer, intent(inout) :: stat
    if (.not. allocated(self%output) .or. self%started) return
    call lock_io()
    call self%output%on_start(info, q, p, stat)
    call unlock_io()
    self%started = .true.
    self%direction = info%direction
  end subroutine obs_start

  !> An accepted step: to the output; the callback record starts afresh (a code the line search
  !> absorbed in this step is no cause of a later failure); stop when destroyed meanwhile.
  subroutine obs_step(self, step, t, q, p, lambda, energy, stat)
    class(c_observer_t), intent(inout) :: self
    integer(i8), intent(in) :: step
    real(dp), intent(in) :: t, q(:), p(:), lambda(:), energy
    integer, intent(inout) :: stat
    logical :: pending
    if (allocated(self%output)) then
      call lock_io()
      call self%output%on_step(step, t, q, p, lambda, energy, stat)
      call unlock_io()
    end if
    if (associated(self%owner)) then
      call self%owner%model%record%clear()
      call lock_registry()
      pending = self%owner%destroy_pending
      call unlock_registry()
      if (pending .and. stat == 0) then
        self%stopped_by_destroy = .true.
        stat = 1
      end if
    end if
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
    if (allocated(self%output) .and. stat == 0) then
      call lock_io()
      call self%output%on_impact(impact, stat)
      call unlock_io()
    end if
  end subroutine obs_impact

  ! a step the safety net split: the output records it (HDF5 attribute split_steps, CSV comment)
  subroutine obs_split(self, step, parts, stat)
    class(c_observer_t), intent(inout) :: self
    integer(i8), intent(in) :: step
    integer, intent(in) :: parts
    integer, intent(inout) :: stat
    if (allocated(self%output)) then
      call lock_io()
      call self%output%on_split(step, parts, stat)
      call unlock_io()
    end if
  end subroutine obs_split

  ! checkpoints go to the output (HDF5 stores them: restarts from its file continue bit for bit)
  pure logical function obs_keeps_checkpoints(self)
    class(c_observer_t), intent(in) :: self
    obs_keeps_checkpoints = .false.
    if (allocated(self%output)) obs_keeps_checkpoints = self%output%keeps_checkpoints()
  end function obs_keeps_checkpoints

  pure logical function obs_wants_checkpoint(self)
    class(c_observer_t), intent(in) :: self
    obs_wants_checkpoint = .false.
    if (allocated(self%output)) obs_wants_checkpoint = self%output%wants_checkpoint()
  end function obs_wants_checkpoint

  subroutine obs_checkpoint(self, cp, stat)
    class(c_observer_t), intent(inout) :: self
    type(vci_checkpoint_t), intent(in) :: cp
    integer, intent(inout) :: stat
    if (allocated(self%output)) call self%output%on_checkpoint(cp, stat)
  end subroutine obs_checkpoint

  subroutine obs_failure_cause(self, cause)
    class(c_observer_t), intent(in) :: self
    character(len=*), intent(out) :: cause
    cause = ''
    if (allocated(self%output)) call self%output%failure_cause(cause)
  end subroutine obs_failure_cause

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
    integer :: cstat
    stat = 0
    if (.not. allocated(ip%obs%output)) return
    ! also when no step was written: the writer then just closes its file
    call lock_io()
    cstat = VCI_OK
    if (ip%obs%started .and. ip%obs%output%keeps_checkpoints()) then
      ! (no memory for it: the file is still finished, without the last state's checkpoint)
      call ip%integ%checkpoint_to(ip%obs%output, cstat)
    end if
    stat = 0
    call ip%obs%output%on_finish(ip%obs%run_status, trim(ip%obs%run_message), stat)
    deallocate (ip%obs%output)
    call unlock_io()
    ip%obs%started = .false.
    ip%obs%direction = 0
    ip%obs%run_status = 0; ip%obs%run_message = ''
    if (stat /= 0) stat = VCI_ERR_IO
    if (stat == VCI_OK .and. cstat == VCI_ERR_MEMORY) stat = VCI_ERR_MEMORY
  end function close_output

  !> After a vci_step/vci_integrate call (its status `stat`, the integrator's message): the end of
  !> the run the open output records so far.
  subroutine note_run_end(ip, stat)
    type(c_integrator_t), intent(inout) :: ip
    integer, intent(in) :: stat
    if (.not. (allocated(ip%obs%output) .and. ip%obs%started)) return
    ip%obs%run_status = stat
    ip%obs%run_message = ''
    if (stat /= VCI_OK) ip%obs%run_message = ip%integ%message_text()
  end subroutine note_run_end

  !> Close the output and release an integrator no handle names any more.
  subroutine free_integrator(ip)
    type(c_integrator_t), pointer, intent(inout) :: ip
    integer :: stat
    stat = close_output(ip)
    if (stat /= VCI_OK) call set_thread_message('vci_integrator_destroy: the output file could not be finished')
    deallocate (ip)
  end subroutine free_integrator

end module vci_capi_registry
