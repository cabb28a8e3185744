(define (problem deliver-one) (:domain courier)
  (:objects van depot shop box)
  (:init (robot van) (place depot) (place shop) (parcel box) (at van depot) (lies box depot) (empty van) (link depot shop))
  (:goal (lies box shop)))
