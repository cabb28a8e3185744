; The rover fetches the box from the store: drive there, grab it.
(define (problem fetch-box)
  (:domain courier)
  (:objects rover - robot lab store - room box - parcel)
  (:init (robot-at rover lab) (door lab store) (door store lab)
         (parcel-at box store) (gripper-free rover))
  (:goal (carrying rover box)))
