!> Newton matrices with a declared sparse pattern (issue 28): a leading block of nb unknowns whose
!> entries vanish outside a pattern the model declares (compressed columns), bordered by nx - nb
!> dense rows and columns (constraint multipliers, the impact fraction alpha or the impulse mu).
!> The whole bordered matrix is factorised by SuiteSparse KLU (vci_klu.c) in compressed-column
!> form: the symbolic analysis (fill-reducing order) once per system size, then per Newton matrix
!> KLU's refactor path (the last pivot order, no search) while its pivots stay regular, else a new
!> factorisation with pivoting (docs/DESIGN.md, "Structured Newton matrices").
!>
!> Optional at build time (CMake VCI_SPARSE): without KLU, sparse_available() is false and the
!> stepper refuses a declared pattern with a status naming the option.
!>
!> The factors live in C memory. A vci_sparse_lu_t frees them when it is finalised or reset; its
!> assignment copies no factors (the copy analyses again on first use), so no two objects ever
!> own the same C memory.
module vci_sparse
  use, intrinsic :: iso_c_binding, only: c_int, c_double, c_ptr, c_null_ptr, c_associated
  use vci_kinds, only: dp
  use vci_kernels, only: invert_row_sizes
  use vci_factor, only: vci_factor_t
  implicit none
  private

  !> Factorised system sizes kept at once (regular sub-step, impact stage, and two spare).
  integer, parameter :: max_slots = 4

  !> The declared pattern of the Hessian blocks: n columns, column j's rows rowind(colptr(j) :
  !> colptr(j + 1) - 1) (1-based, sorted, no repeats, the diagonal included, symmetric).
  type, public :: vci_sparse_pattern_t
    integer :: n = 0                      !< columns (0: no pattern declared)
    integer, allocatable :: colptr(:)     !< n + 1 column starts into rowind
    integer, allocatable :: rowind(:)     !< row indices, column by column
    !> tpos(k): the place in rowind of the transpose of entry k (the pattern is symmetric)
    integer, allocatable :: tpos(:)
    !> upos(k): the place in rowind of the k-th entry as declared (the declared rowind's order,
    !> which a sparse Hessian callback gives its values in; repeats map to the same place)
    integer, allocatable :: upos(:)
  end type vci_sparse_pattern_t

  !> One analysed pattern (a system size) and its last numeric factors.
  type :: klu_slot_t
    integer :: nx = 0, nb = 0, nnz_block = 0, used = 0
    type(c_ptr) :: handle = c_null_ptr
    integer(c_int), allocatable :: ap(:), ai(:)
    real(c_double), allocatable :: ax(:)
  end type klu_slot_t

  !> Sparse LU factors of bordered Newton matrices (factor, then solve any number of times).
  type, extends(vci_factor_t), public :: vci_sparse_lu_t
    integer, private :: last = 0          !< slot of the last factorisation
    integer, private :: clock = 0
    type(klu_slot_t), private :: slot(max_slots)
  contains
    !> Factorise diag(rw) jac(1:nx, 1:nx): block nb with the pattern pat, a dense border.
    procedure :: factor
    !> The same from the matrix's parts (block values in pattern order, border rows and columns).
    procedure :: factor_parts
    !> b(1:nx) := matrix^{-1} b with the last factors.
    procedure :: solve
    !> Free every factor and analysis (C memory).
    procedure :: reset
    !> Assignment copies no factors: the target is reset.
    procedure, private :: assign_empty
    generic :: assignment(=) => assign_empty
    final :: finalise
  end type vci_sparse_lu_t

  interface
    integer(c_int) function vci_klu_available() bind(c, name='vci_klu_available')
      import :: c_int
    end function vci_klu_available
    type(c_ptr) function vci_klu_analyze(n, ap, ai) bind(c, name='vci_klu_analyze')
      import :: c_int, c_ptr
      integer(c_int), value :: n
      integer(c_int), intent(in) :: ap(*), ai(*)
    end function vci_klu_analyze
    integer(c_int) function vci_klu_factor(h, ap, ai, ax) bind(c, name='vci_klu_factor')
      import :: c_int, c_ptr, c_double
      type(c_ptr), value :: h
      integer(c_int), intent(in) :: ap(*), ai(*)
      real(c_double), intent(in) :: ax(*)
    end function vci_klu_factor
    integer(c_int) function vci_klu_solve(h, b) bind(c, name='vci_klu_solve')
      import :: c_int, c_ptr, c_double
      type(c_ptr), value :: h
      real(c_double), intent(inout) :: b(*)
    end function vci_klu_solve
    subroutine vci_klu_free(h) bind(c, name='vci_klu_free')
      import :: c_ptr
      type(c_ptr), value :: h
    end subroutine vci_klu_free
  end interface

  public :: sparse_available, make_pattern, outside_pattern, pattern_rows, pattern_arrays_error, pattern_find

contains

  !> Was the library built with the sparse solver (CMake VCI_SPARSE, SuiteSparse KLU)?
  logical function sparse_available()
    sparse_available = vci_klu_available() /= 0
  end function sparse_available

  !> pat := the pattern of n columns given as compressed columns (colptr(n + 1), 1-based rows
  !> rowind, any order, repeats allowed), made symmetric and given its diagonal. stat 0: done;
  !> 1: colptr or rowind out of range (msg says which); 2: out of memory.
  subroutine make_pattern(n, colptr, rowind, pat, stat, msg)
    integer, intent(in) :: n, colptr(:), rowind(:)
    type(vci_sparse_pattern_t), intent(out) :: pat
    integer, intent(out) :: stat
    character(len=*), intent(out) :: msg
    integer, allocatable :: stamp(:), start(:), rows(:), pi(:), pj(:)
    integer :: i, j, k, nnz, np, q
    stat = 1; msg = ''
    if (n < 1 .or. size(colptr) < n + 1) then
      msg = 'the pattern needs n >= 1 and n + 1 column pointers'; return
    end if
    if (colptr(1) /= 1 .or. any(colptr(2:n + 1) < colptr(1:n)) .or. colptr(n + 1) - 1 > size(rowind)) then
      msg = 'the column pointers must start at 1, not decrease and end within the row indices'; return
    end if
    nnz = colptr(n + 1) - 1
    if (nnz > 0) then
      if (any(rowind(1:nnz) < 1) .or. any(rowind(1:nnz) > n)) then
        msg = 'a row index of the pattern is outside 1..n'; return
      end if
    end if
    ! the entries (i, j), their transposes and the diagonal, grouped by column (counting sort)
    np = 2 * nnz + n
    allocate (pi(np), pj(np), stamp(n), start(n + 1), rows(np), stat=stat)
    if (stat /= 0) then
      stat = 2; msg = 'out of memory for the pattern'; return
    end if
    np = 0
    do j = 1, n
      np = np + 1; pi(np) = j; pj(np) = j
      do k = colptr(j), colptr(j + 1) - 1
        np = np + 1; pi(np) = rowind(k); pj(np) = j
        np = np + 1; pi(np) = j; pj(np) = rowind(k)
      end do
    end do
    start = 0
    do k = 1, np
      start(pj(k) + 1) = start(pj(k) + 1) + 1
    end do
    start(1) = 1
    do j = 1, n
      start(j + 1) = start(j + 1) + start(j)
    end do
    stamp = start(1:n)               ! (next free place of each column)
    do k = 1, np
      rows(stamp(pj(k))) = pi(k); stamp(pj(k)) = stamp(pj(k)) + 1
    end do
    ! each column's rows without repeats, sorted
    allocate (pat%colptr(n + 1), pat%rowind(np), stat=stat)
    if (stat /= 0) then
      stat = 2; msg = 'out of memory for the pattern'; return
    end if
    stamp = 0
    q = 0
    pat%colptr(1) = 1
    do j = 1, n
      do k = start(j), start(j + 1) - 1
        i = rows(k)
        if (stamp(i) == j) cycle
        stamp(i) = j
        q = q + 1; pat%rowind(q) = i
      end do
      pat%colptr(j + 1) = q + 1
      call sort_rows(pat%rowind(pat%colptr(j):q))
    end do
    pat%n = n
    ! where each entry's transpose and each declared entry sit (O(nnz log) searches, once)
    allocate (pat%tpos(q), pat%upos(nnz), stat=stat)
    if (stat /= 0) then
      stat = 2; msg = 'out of memory for the pattern'; pat%n = 0; return
    end if
    do j = 1, n
      do k = pat%colptr(j), pat%colptr(j + 1) - 1
        pat%tpos(k) = pattern_find(pat, j, pat%rowind(k))
      end do
      do k = colptr(j), colptr(j + 1) - 1
        pat%upos(k) = pattern_find(pat, rowind(k), j)
      end do
    end do
    stat = 0
  end subroutine make_pattern

  !> The place in pat%rowind of entry (i, j), or 0 when it is outside the pattern (binary search
  !> in column j's sorted rows).
  pure integer function pattern_find(pat, i, j) result(k)
    type(vci_sparse_pattern_t), intent(in) :: pat
    integer, intent(in) :: i, j
    integer :: lo, hi, mid
    k = 0
    if (j < 1 .or. j > pat%n) return
    lo = pat%colptr(j); hi = pat%colptr(j + 1) - 1
    do while (lo <= hi)
      mid = (lo + hi) / 2
      if (pat%rowind(mid) == i) then
        k = mid; return
      else if (pat%rowind(mid) < i) then
        lo = mid + 1
      else
        hi = mid - 1
      end if
    end do
  end function pattern_find

  !> The strict check of a pattern given through the C or legacy entry (make_pattern itself is
  !> lenient): colptr(1:n + 1) starts at base and never decreases, column j's rows
  !> rowind(colptr(j) - base + 1 : colptr(j + 1) - base) lie in base..n - 1 + base and strictly
  !> increase. msg = '' when it holds, else the first fault, naming the arrays as the caller calls
  !> them (cname, rname) with the caller's indices (base 0: name[k]; base 1: name(k)).
  subroutine pattern_arrays_error(n, colptr, rowind, base, cname, rname, msg)
    integer, intent(in) :: n, colptr(:), rowind(:), base
    character(len=*), intent(in) :: cname, rname
    character(len=*), intent(out) :: msg
    integer :: j, k, r
    msg = ''
    if (colptr(1) /= base) then
      msg = at(cname, 1)//' = '//itoa(colptr(1))//', not '//itoa(base); return
    end if
    do j = 1, n
      if (colptr(j + 1) < colptr(j)) then
        msg = cname//' decreases: '//at(cname, j + 1)//' = '//itoa(colptr(j + 1))//' < '//at(cname, j)// &
              ' = '//itoa(colptr(j)); return
      end if
    end do
    if (colptr(n + 1) - base > size(rowind)) then
      msg = at(cname, n + 1)//' = '//itoa(colptr(n + 1))//' goes past the '//itoa(size(rowind))//' row indices'
      return
    end if
    do j = 1, n
      do k = colptr(j) - base + 1, colptr(j + 1) - base
        r = rowind(k)
        if (r < base .or. r > n - 1 + base) then
          msg = at(rname, k)//' = '//itoa(r)//' (column '//itoa(j - 1 + base)//') is outside '//itoa(base)//'..'// &
                itoa(n - 1 + base); return
        else if (k > colptr(j) - base + 1) then
          if (r <= rowind(k - 1)) then
            msg = 'the rows of column '//itoa(j - 1 + base)//' are not strictly increasing at '//at(rname, k)// &
                  ' = '//itoa(r)//' (sorted, no repeats)'; return
          end if
        end if
      end do
    end do
  contains
    !> name[k - 1] (base 0) or name(k) (base 1): element k of an array as the caller writes it.
    function at(name, k) result(s)
      character(len=*), intent(in) :: name
      integer, intent(in) :: k
      character(len=:), allocatable :: s
      if (base == 0) then
        s = name//'['//itoa(k - 1)//']'
      else
        s = name//'('//itoa(k)//')'
      end if
    end function at
    function itoa(i) result(s)
      integer, intent(in) :: i
      character(len=:), allocatable :: s
      character(len=12) :: buf
      write (buf, '(i0)') i
      s = trim(buf)
    end function itoa
  end subroutine pattern_arrays_error

  !> The first entry (i, j) of the block (i, j <= nb) outside the pattern with a(i, j) /= 0
  !> (column by column), or i = j = 0 (the debug check of a declared pattern; O(nb^2)).
  subroutine outside_pattern(nb, pat, a, lda, i, j)
    integer, intent(in) :: nb, lda
    type(vci_sparse_pattern_t), intent(in) :: pat
    real(dp), intent(in) :: a(lda, *)
    integer, intent(out) :: i, j
    integer :: k, r
    do j = 1, nb
      k = pat%colptr(j)
      do r = 1, nb
        if (k < pat%colptr(j + 1)) then
          if (pat%rowind(k) == r) then
            k = k + 1; cycle
          end if
        end if
        if (a(r, j) /= 0.0_dp) then
          i = r; return
        end if
      end do
    end do
    i = 0; j = 0
  end subroutine outside_pattern

  !> rw(i) = 1 / the largest |a(i, j)| of row i over the pattern and the border (entries outside
  !> the pattern are not read); returns the sum of those maxima (not finite: a NaN or Inf).
  real(dp) function pattern_rows(n, nb, pat, a, lda, rw) result(total)
    integer, intent(in) :: n, nb, lda
    type(vci_sparse_pattern_t), intent(in) :: pat
    real(dp), intent(in) :: a(lda, *)
    real(dp), intent(out) :: rw(:)
    integer :: i, j, k
    rw(1:n) = 0.0_dp
    do j = 1, n
      if (j <= nb) then
        do k = pat%colptr(j), pat%colptr(j + 1) - 1
          i = pat%rowind(k)
          rw(i) = max(rw(i), abs(a(i, j)))
        end do
        do i = nb + 1, n
          rw(i) = max(rw(i), abs(a(i, j)))
        end do
      else
        do i = 1, n
          rw(i) = max(rw(i), abs(a(i, j)))
        end do
      end if
    end do
    call invert_row_sizes(n, rw, total)
  end function pattern_rows

  !> Factorise diag(rw) jac(1:nx, 1:nx) (rows scaled as the values are gathered; jac is not
  !> changed): the block of nb unknowns in the pattern pat, the last nx - nb rows and columns
  !> dense. info: 0 done; 1 singular or numerically so (pivots below 1e-14 of the largest);
  !> -1 not built with KLU, or no memory. The caller then factorises densely.
  subroutine factor(self, nx, nb, pat, jac, ld, rw, info)
    class(vci_sparse_lu_t), intent(inout) :: self
    integer, intent(in) :: nx, nb, ld
    type(vci_sparse_pattern_t), intent(in) :: pat
    real(dp), intent(in) :: jac(ld, *), rw(*)
    integer, intent(out) :: info
    integer :: s, i, j, k, q
    s = claim_slot(self, nx, nb, pat, info)
    if (s == 0) return
    associate (ax => self%slot(s)%ax)
      q = 0
      do j = 1, nx
        if (j <= nb) then
          do k = pat%colptr(j), pat%colptr(j + 1) - 1
            i = pat%rowind(k)
            q = q + 1; ax(q) = rw(i) * jac(i, j)
          end do
          do i = nb + 1, nx
            q = q + 1; ax(q) = rw(i) * jac(i, j)
          end do
        else
          do i = 1, nx
            q = q + 1; ax(q) = rw(i) * jac(i, j)
          end do
        end if
      end do
    end associate
    call factor_slot(self, s, info)
  end subroutine factor

  !> factor from the matrix's parts, as vci_sparse_matrix keeps them (no dense copy): the block's
  !> values val(1:nnz) in pat's order, the border rows rows(k, j) = A(nb + k, j) for j <= nb and
  !> the border columns cols(i, k) = A(i, nb + k); rows scaled by rw. info as factor's.
  subroutine factor_parts(self, nx, nb, pat, val, rows, cols, rw, info)
    class(vci_sparse_lu_t), intent(inout) :: self
    integer, intent(in) :: nx, nb
    type(vci_sparse_pattern_t), intent(in) :: pat
    real(dp), intent(in) :: val(:), rows(:, :), cols(:, :), rw(*)
    integer, intent(out) :: info
    integer :: s, i, j, k, q
    s = claim_slot(self, nx, nb, pat, info)
    if (s == 0) return
    associate (ax => self%slot(s)%ax)
      q = 0
      do j = 1, nx
        if (j <= nb) then
          do k = pat%colptr(j), pat%colptr(j + 1) - 1
            q = q + 1; ax(q) = rw(pat%rowind(k)) * val(k)
          end do
          do i = nb + 1, nx
            q = q + 1; ax(q) = rw(i) * rows(i - nb, j)
          end do
        else
          do i = 1, nx
            q = q + 1; ax(q) = rw(i) * cols(i, j - nb)
          end do
        end if
      end do
    end associate
    call factor_slot(self, s, info)
  end subroutine factor_parts

  !> What factor and factor_parts do before gathering the values (where the values come from is
  !> all that differs between them): no factors until new ones succeed, the sizes checked, the slot
  !> analysed for (nx, nb, pat). 0 with info = -1: wrong sizes, no KLU or no memory.
  integer function claim_slot(self, nx, nb, pat, info) result(s)
    type(vci_sparse_lu_t), intent(inout) :: self
    integer, intent(in) :: nx, nb
    type(vci_sparse_pattern_t), intent(in) :: pat
    integer, intent(out) :: info
    self%ready = .false.
    info = -1
    s = 0
    if (nb < 1 .or. nb > nx .or. pat%n /= nb) return
    s = find_slot(self, nx, nb, pat)
  end function claim_slot

  !> KLU on slot s's gathered values; its factors become the last ones (ready when info = 0).
  subroutine factor_slot(self, s, info)
    type(vci_sparse_lu_t), intent(inout) :: self
    integer, intent(in) :: s
    integer, intent(out) :: info
    info = vci_klu_factor(self%slot(s)%handle, self%slot(s)%ap, self%slot(s)%ai, self%slot(s)%ax)
    self%last = s
    self%ready = info == 0
  end subroutine factor_slot

  !> b(1:nx) := matrix^{-1} b with the last factors (b unchanged when there are none).
  subroutine solve(self, b)
    class(vci_sparse_lu_t), intent(inout) :: self
    real(dp), intent(inout) :: b(:)
    integer :: info
    if (.not. self%ready .or. self%last == 0) return
    if (size(b) /= self%slot(self%last)%nx) return
    info = vci_klu_solve(self%slot(self%last)%handle, b)
  end subroutine solve

  !> The slot analysed for (nx, nb, pat), analysing it (in the least recently used slot) if
  !> needed; 0: no KLU, or no memory.
  integer function find_slot(self, nx, nb, pat) result(s)
    type(vci_sparse_lu_t), intent(inout) :: self
    integer, intent(in) :: nx, nb
    type(vci_sparse_pattern_t), intent(in) :: pat
    integer :: k, j, i, q, nnz, st, oldest
    self%clock = self%clock + 1
    nnz = pat%colptr(nb + 1) - 1
    do s = 1, max_slots
      if (self%slot(s)%nx == nx .and. self%slot(s)%nb == nb .and. self%slot(s)%nnz_block == nnz .and. &
          c_associated(self%slot(s)%handle)) then
        ! the sizes alone do not name the analysis: another pattern of as many entries gathers its
        ! values in another order (O(nnz) integer compares, next to a numeric factorisation)
        if (.not. same_block(self%slot(s), nb, pat)) cycle
        self%slot(s)%used = self%clock; return
      end if
    end do
    oldest = huge(1); s = 1
    do k = 1, max_slots
      if (self%slot(k)%used < oldest) then
        oldest = self%slot(k)%used; s = k
      end if
    end do
    call free_slot(self%slot(s))
    associate (sl => self%slot(s))
      allocate (sl%ap(nx + 1), sl%ai(nnz + nb * (nx - nb) + (nx - nb) * nx), stat=st)
      if (st == 0) allocate (sl%ax(size(sl%ai)), stat=st)
      if (st /= 0) then
        call free_slot(sl); s = 0; return
      end if
      ! 0-based compressed columns: block columns (pattern rows, then the border rows), border columns
      q = 0
      do j = 1, nx
        sl%ap(j) = q
        if (j <= nb) then
          do k = pat%colptr(j), pat%colptr(j + 1) - 1
            sl%ai(q + 1) = pat%rowind(k) - 1; q = q + 1
          end do
          do i = nb + 1, nx
            sl%ai(q + 1) = i - 1; q = q + 1
          end do
        else
          do i = 1, nx
            sl%ai(q + 1) = i - 1; q = q + 1
          end do
        end if
      end do
      sl%ap(nx + 1) = q
      sl%handle = vci_klu_analyze(int(nx, c_int), sl%ap, sl%ai)
      if (.not. c_associated(sl%handle)) then
        call free_slot(sl); s = 0; return
      end if
      sl%nx = nx; sl%nb = nb; sl%nnz_block = nnz; sl%used = self%clock
    end associate
  end function find_slot

  !> Was slot sl analysed for pat's block (its nb columns' rows, in order)?
  logical function same_block(sl, nb, pat)
    type(klu_slot_t), intent(in) :: sl
    integer, intent(in) :: nb
    type(vci_sparse_pattern_t), intent(in) :: pat
    integer :: j, k, q
    same_block = .false.
    do j = 1, nb
      q = sl%ap(j)
      if (sl%ap(j + 1) - q /= pat%colptr(j + 1) - pat%colptr(j) + (sl%nx - nb)) return
      do k = pat%colptr(j), pat%colptr(j + 1) - 1
        q = q + 1
        if (sl%ai(q) /= pat%rowind(k) - 1) return
      end do
    end do
    same_block = .true.
  end function same_block

  !> Free one slot's analysis, factors and arrays.
  subroutine free_slot(sl)
    type(klu_slot_t), intent(inout) :: sl
    if (c_associated(sl%handle)) call vci_klu_free(sl%handle)
    sl%handle = c_null_ptr
    sl%nx = 0; sl%nb = 0; sl%nnz_block = 0; sl%used = 0
    if (allocated(sl%ap)) deallocate (sl%ap)
    if (allocated(sl%ai)) deallocate (sl%ai)
    if (allocated(sl%ax)) deallocate (sl%ax)
  end subroutine free_slot

  !> Free every factor and analysis.
  subroutine reset(self)
    class(vci_sparse_lu_t), intent(inout) :: self
    integer :: s
    do s = 1, max_slots
      call free_slot(self%slot(s))
    end do
    self%ready = .false.; self%last = 0; self%clock = 0
  end subroutine reset

  !> self = other: copies no factors (C memory has one owner); self starts empty.
  subroutine assign_empty(self, other)
    class(vci_sparse_lu_t), intent(inout) :: self
    type(vci_sparse_lu_t), intent(in) :: other
    call self%reset()
  end subroutine assign_empty

  subroutine finalise(self)
    type(vci_sparse_lu_t), intent(inout) :: self
    call self%reset()
  end subroutine finalise

  !> Sort a short list of integers in place (insertion sort).
  pure subroutine sort_rows(a)
    integer, intent(inout) :: a(:)
    integer :: i, k, v
    do i = 2, size(a)
      v = a(i); k = i - 1
      do while (k >= 1)
        if (a(k) <= v) exit
        a(k + 1) = a(k); k = k - 1
      end do
      a(k + 1) = v
    end do
  end subroutine sort_rows
end module vci_sparse
