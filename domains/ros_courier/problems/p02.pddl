; Two parcels, to the lab and to the office.
(define (problem two-parcels)
  (:domain ros-courier)
  (:objects
    courier - robot
    mailroom hall lab office - place
    parcel-1 parcel-2 - parcel)
  (:init
    (at courier mailroom) (lost courier) (empty-handed courier)
    (road mailroom hall) (road hall mailroom)
    (road hall lab) (road lab hall)
    (road hall office) (road office hall)
    (parcel-at parcel-1 mailroom) (addressed-to parcel-1 lab)
    (parcel-at parcel-2 mailroom) (addressed-to parcel-2 office))
  (:goal (and (delivered parcel-1) (delivered parcel-2))))
