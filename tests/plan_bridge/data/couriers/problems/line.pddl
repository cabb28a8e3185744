; Rooms west - mid - east - annex in a line, a store no door reaches; one courier at
; each end of the line, three parcels.
(define (problem line)
  (:domain couriers)
  (:objects
    ann bo - courier
    west mid east annex store - room
    p1 p2 p3 p4 - parcel)
  (:init
    (in ann west) (free ann)
    (in bo annex) (free bo)
    (door west mid) (door mid west)
    (door mid east) (door east mid)
    (door east annex) (door annex east)
    (lies p1 mid) (lies p2 east) (lies p3 west) (lies p4 store))
  (:goal (and (lies p1 annex))))
