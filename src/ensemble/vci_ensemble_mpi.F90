!> The ensemble driver that writes one HDF5 file (layout: docs/ENSEMBLES.md). Built with MPI
!> (VCI_HAVE_MPI) it spreads the members over the ranks of a communicator and all ranks write the
!> file together through parallel HDF5; built without MPI the same loop runs in one process.
!>
!> Load balance is dynamic (self-scheduling): a shared counter on rank 0, advanced with
!> MPI_Fetch_and_op (passive-target one-sided communication), hands out blocks of consecutive
!> members to whichever rank asks next — `chunk` of them, or (chunk = 0) blocks that shrink as the
!> members run out (guided self-scheduling); each rank's OpenMP threads run the block (dynamic
!> schedule) and the rank writes it to the file at once (independent I/O) and asks again.
!> Impact-rich members cost more than others, so a fixed split would leave ranks idle.
!>
!> Results do not depend on the number of ranks, threads, or on the chunk: each member is run by
!> vci_ensemble_run_member with its own model and integrator and lands at its own index.
!> MPI is called only from the thread that called this routine, outside parallel regions
!> (MPI_THREAD_FUNNELED is enough).
module vci_ensemble_mpi
#ifdef VCI_HAVE_MPI
  use, intrinsic :: iso_c_binding, only: c_ptr
  use mpi_f08
#endif
  !$ use omp_lib, only: omp_get_max_threads
  use vci_kinds, only: dp, i8
  use vci_status
  use vci_ensemble, only: vci_model_factory_t, vci_ensemble_config_t, vci_ensemble_table_t, &
                          vci_ensemble_results_t, vci_ensemble_check, vci_ensemble_results_alloc, &
                          vci_ensemble_run_member, vci_ensemble_size
  use vci_ensemble_h5, only: vci_ensemble_file_t
  implicit none
  private

  public :: vci_ensemble_run_file

contains

  !> Run every member of `table` and write all results to the HDF5 file `path` (an existing file is
  !> kept, VCI_ERR_IO, unless `overwrite`). Under MPI this is collective over `comm` (default
  !> MPI_COMM_WORLD, which must be initialised), every rank passing the same factory, configuration
  !> and table; `stat` and `message` are then the same on every rank.
  !> `stat` is VCI_OK when every member was run and written, whatever the members' own statuses
  !> (`members_failed` counts those); VCI_ERR_ARGUMENT, VCI_ERR_STATE, VCI_ERR_MEMORY (the results
  !> of a block, the file writer's buffers) or VCI_ERR_IO otherwise.
#ifdef VCI_HAVE_MPI
  subroutine vci_ensemble_run_file(factory, config, table, path, stat, message, overwrite, &
                                   members_failed, comm)
#else
  subroutine vci_ensemble_run_file(factory, config, table, path, stat, message, overwrite, &
                                   members_failed)
#endif
    class(vci_model_factory_t), intent(in) :: factory
    type(vci_ensemble_config_t), intent(in) :: config
    type(vci_ensemble_table_t), intent(in) :: table
    character(len=*), intent(in) :: path
    integer, intent(out) :: stat
    character(len=*), intent(out), optional :: message
    logical, intent(in), optional :: overwrite
    integer, intent(out), optional :: members_failed
#ifdef VCI_HAVE_MPI
    type(MPI_Comm), intent(in), optional :: comm
    type(MPI_Comm) :: com
    type(MPI_Win) :: win
    integer :: ierr
    logical :: flag
    integer :: sums(2), stats(2)
#endif
    type(vci_ensemble_file_t) :: file
    type(vci_ensemble_results_t) :: res
    character(len=VCI_MSG_LEN) :: msg
    integer :: rank, nranks, nt, chunk, n_members, first, cnt, i, s, run, failed, share0, share1, take
    integer(i8) :: next_local, first8, taken

    rank = 0; nranks = 1
    msg = ''
    run = 0; failed = 0
    if (present(members_failed)) members_failed = 0
#ifdef VCI_HAVE_MPI
    call MPI_Initialized(flag, ierr)
    if (.not. flag) then
      stat = VCI_ERR_STATE
      if (present(message)) message = 'ensemble: MPI is not initialised (call MPI_Init_thread first)'
      return
    end if
    com = MPI_COMM_WORLD
    if (present(comm)) com = comm
    call MPI_Comm_rank(com, rank, ierr)
    call MPI_Comm_size(com, nranks, ierr)
#endif
    call vci_ensemble_check(config, table, stat, msg)
#ifdef VCI_HAVE_MPI
    ! every rank must see the same ensemble: compare the member counts (the cheap part of that)
    n_members = vci_ensemble_size(table)
    sums = [n_members, -n_members]
    call MPI_Allreduce(MPI_IN_PLACE, sums, 2, MPI_INTEGER, MPI_MAX, com, ierr)
    if (stat == VCI_OK .and. sums(1) /= -sums(2)) then
      stat = VCI_ERR_ARGUMENT
      msg = 'ensemble: the ranks were given tables of different sizes'
    end if
    call agree(stat, msg, com)
#endif
    if (stat /= VCI_OK) then
      if (present(message)) message = msg
      return
    end if
    n_members = vci_ensemble_size(table)
    nt = max(1, config%threads)
    !$ if (config%threads <= 0) nt = omp_get_max_threads()
    ! the chunk recorded in the file: the fixed one, or the largest automatic one
    chunk = config%chunk
    if (chunk <= 0) chunk = max_auto_chunk(nt)

#ifdef VCI_HAVE_MPI
    call file%create(path, config, table, nranks, nt, chunk, stat, overwrite, com)
#else
    call file%create(path, config, table, nranks, nt, chunk, stat, overwrite)
#endif
    msg = file%message
    ! the table: each rank writes its share of consecutive members
    share0 = int(int(n_members, i8) * rank / nranks) + 1
    share1 = int(int(n_members, i8) * (rank + 1) / nranks)
    if (stat == VCI_OK) call file%write_table(table, share0, share1 - share0 + 1, stat)
    if (stat /= VCI_OK .and. msg == '') msg = file%message
#ifdef VCI_HAVE_MPI
    call agree(stat, msg, com)
#endif
    if (stat /= VCI_OK) then
      call file%abandon()        ! (create removed its file itself when it failed)
      if (present(message)) message = msg
      return
    end if

#ifdef VCI_HAVE_MPI
    call counter_open(com, rank, win)
#endif
    next_local = 0
    taken = 0
    do
      take = claim_size(config%chunk, nt, nranks, int(max(0_i8, n_members - taken)))
      ! 64-bit: the counter passes n_members by up to a claim a rank (a chunk may be huge(1))
#ifdef VCI_HAVE_MPI
      first8 = counter_take(win, take) + 1
#else
      first8 = next_local + 1
      next_local = next_local + take
#endif
      if (first8 > n_members) exit
      first = int(first8)
      taken = first8 - 1 + take          ! members handed out, as far as this rank knows
      cnt = int(min(int(take, i8), n_members - first8 + 1))
      call vci_ensemble_results_alloc(res, config, size(table%q0, 1), first, cnt, stat, msg)
      if (stat /= VCI_OK) then
#ifdef VCI_HAVE_MPI
        call counter_stop(win, n_members)
#endif
        exit
      end if
      !$omp parallel do num_threads(nt) schedule(dynamic, 1) default(none) &
      !$omp   shared(factory, config, table, res, first, cnt) private(i)
      do i = first, first + cnt - 1
        call vci_ensemble_run_member(factory, config, table, i, res)
      end do
      !$omp end parallel do
      call file%write_results(res, rank, stat)
      if (stat /= VCI_OK) then
        msg = file%message
        ! the file takes no more members (a full disk is every rank's): the others stop claiming,
        ! finish the block they hold, and meet this rank at the collective calls below
#ifdef VCI_HAVE_MPI
        call counter_stop(win, n_members)
#endif
        exit
      end if
      run = run + cnt
      failed = failed + count(res%status /= VCI_OK)
    end do
#ifdef VCI_HAVE_MPI
    call counter_close(win)
    stats = [run, failed]
    call MPI_Allreduce(MPI_IN_PLACE, stats, 2, MPI_INTEGER, MPI_SUM, com, ierr)
    run = stats(1); failed = stats(2)
    call agree(stat, msg, com)
#endif
    if (stat /= VCI_OK) then
      call file%abandon()     ! every rank knows: no rank writes the totals of a file that failed
    else
      call file%close(run, failed, s)
      if (s /= VCI_OK) then
        stat = s; msg = file%message
      end if
    end if
#ifdef VCI_HAVE_MPI
    call agree(stat, msg, com)
#endif
    if (stat == VCI_OK .and. run /= n_members) then
      stat = VCI_ERR_IO
      write (msg, '(a,i0,a,i0,a)') 'ensemble: only ', run, ' of ', n_members, ' members were written'
    end if
    if (present(members_failed)) members_failed = failed
    if (present(message)) message = msg
  end subroutine vci_ensemble_run_file

  !> Largest automatic claim: 64 members per thread (bounds a block's memory and makes its writes
  !> worth their cost; the parallel loop's barrier comes once a block).
  pure integer function max_auto_chunk(nt)
    integer, intent(in) :: nt
    max_auto_chunk = 64 * nt
  end function max_auto_chunk

  !> Members to claim next: `fixed` when given, else guided self-scheduling: a quarter of an even
  !> share of what remains, between one member per thread and max_auto_chunk, so that claims are
  !> large while much remains (few barriers and writes) and small at the end (ranks finish together).
  pure integer function claim_size(fixed, nt, nranks, remaining) result(take)
    integer, intent(in) :: fixed, nt, nranks, remaining
    if (fixed > 0) then
      take = fixed
    else
      take = max(nt, min(max_auto_chunk(nt), remaining / (4 * nranks)))
    end if
  end function claim_size

#ifdef VCI_HAVE_MPI
  !> Make a status and its message the same on every rank: the worst (largest) status and the
  !> message of the lowest rank that has it.
  subroutine agree(stat, msg, com)
    integer, intent(inout) :: stat
    character(len=*), intent(inout) :: msg
    type(MPI_Comm), intent(in) :: com
    integer :: worst, owner, ierr, rank
    call MPI_Comm_rank(com, rank, ierr)
    call MPI_Allreduce(stat, worst, 1, MPI_INTEGER, MPI_MAX, com, ierr)
    owner = huge(1)
    if (stat == worst) owner = rank
    call MPI_Allreduce(MPI_IN_PLACE, owner, 1, MPI_INTEGER, MPI_MIN, com, ierr)
    call MPI_Bcast(msg, len(msg), MPI_CHARACTER, owner, com, ierr)
    stat = worst
  end subroutine agree

  !> The shared member counter: one 64-bit integer in a window on rank 0, set to 0, and a
  !> passive-target epoch on every rank (collective).
  subroutine counter_open(com, rank, win)
    type(MPI_Comm), intent(in) :: com
    integer, intent(in) :: rank
    type(MPI_Win), intent(out) :: win
    type(c_ptr) :: base
    integer(MPI_ADDRESS_KIND) :: bytes
    integer(i8), asynchronous :: zero
    integer :: ierr
    bytes = 0
    if (rank == 0) bytes = 8
    call MPI_Win_allocate(bytes, 8, MPI_INFO_NULL, com, base, win, ierr)
    if (rank == 0) then
      zero = 0
      call MPI_Win_lock(MPI_LOCK_EXCLUSIVE, 0, 0, win, ierr)
      call MPI_Put(zero, 1, MPI_INTEGER8, 0, 0_MPI_ADDRESS_KIND, 1, MPI_INTEGER8, win, ierr)
      call MPI_Win_unlock(0, win, ierr)
    end if
    call MPI_Barrier(com, ierr)
    call MPI_Win_lock_all(0, win, ierr)
  end subroutine counter_open

  !> Atomically advance the counter by `chunk`; the value before (members already handed out).
  integer(i8) function counter_take(win, chunk) result(before)
    type(MPI_Win), intent(in) :: win
    integer, intent(in) :: chunk
    integer(i8), asynchronous :: inc, old
    integer :: ierr
    inc = chunk
    call MPI_Fetch_and_op(inc, old, MPI_INTEGER8, 0, 0_MPI_ADDRESS_KIND, MPI_SUM, win, ierr)
    call MPI_Win_flush(0, win, ierr)
    before = old
  end function counter_take

  !> Push the counter past the last member: every rank's next claim finds nothing left.
  subroutine counter_stop(win, n_members)
    type(MPI_Win), intent(in) :: win
    integer, intent(in) :: n_members
    integer(i8) :: before
    before = counter_take(win, n_members)
  end subroutine counter_stop

  subroutine counter_close(win)
    type(MPI_Win), intent(inout) :: win
    integer :: ierr
    call MPI_Win_unlock_all(win, ierr)
    call MPI_Win_free(win, ierr)
  end subroutine counter_close
#endif
end module vci_ensemble_mpi
