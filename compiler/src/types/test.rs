use super::*;

fn record(table: &mut TypeTable, packed: bool, fields: &[(&str, Type)]) -> Type {
    let fields = fields
        .iter()
        .map(|(n, t)| (n.to_string(), t.clone()))
        .collect();
    Type::Named(table.defs.push(TypeDef {
        name: "R".into(),
        kind: TypeDefKind::Record { packed, fields },
    }))
}

#[test]
fn primitive_sizes_are_t800_sizes() {
    let t = TypeTable::default();
    let sizes: Vec<u32> = Prim::ALL
        .iter()
        .map(|p| bytes_in(&t, &Type::Prim(*p)).unwrap())
        .collect();
    assert_eq!(sizes, [1, 1, 4, 2, 4, 8, 4, 8]);
}

#[test]
fn arrays_multiply_and_open_arrays_are_unsized() {
    let t = TypeTable::default();
    let a = Type::array(Some(3), Type::array(Some(5), Type::Prim(Prim::Int16)));
    assert_eq!(bytes_in(&t, &a), Ok(30));
    assert_eq!(
        bytes_in(&t, &Type::array(None, Type::INT)),
        Err(LayoutError::Unsized)
    );
    let huge = Type::array(Some(1 << 20), Type::array(Some(1 << 20), Type::INT));
    assert_eq!(bytes_in(&t, &huge), Err(LayoutError::TooLarge));
}

#[test]
fn unpacked_record_pads_fields_to_alignment() {
    let mut t = TypeTable::default();
    let r = record(
        &mut t,
        false,
        &[("b", Type::BYTE), ("i", Type::INT), ("c", Type::BYTE)],
    );
    assert_eq!(offset_of(&t, &r, "b"), Ok(0));
    assert_eq!(offset_of(&t, &r, "i"), Ok(4));
    assert_eq!(offset_of(&t, &r, "c"), Ok(8));
    assert_eq!(bytes_in(&t, &r), Ok(12));
}

#[test]
fn packed_record_has_no_padding() {
    let mut t = TypeTable::default();
    let r = record(
        &mut t,
        true,
        &[
            ("b", Type::BYTE),
            ("i", Type::INT),
            ("s", Type::Prim(Prim::Int16)),
        ],
    );
    assert_eq!(offset_of(&t, &r, "i"), Ok(1));
    assert_eq!(offset_of(&t, &r, "s"), Ok(5));
    assert_eq!(bytes_in(&t, &r), Ok(7));
    assert_eq!(offset_of(&t, &r, "zz"), Err(LayoutError::NoSuchField));
    assert_eq!(offset_of(&t, &Type::INT, "b"), Err(LayoutError::NotRecord));
}

#[test]
fn int64_in_record_aligns_to_a_word_only() {
    let mut t = TypeTable::default();
    let r = record(
        &mut t,
        false,
        &[("b", Type::BYTE), ("l", Type::Prim(Prim::Int64))],
    );
    assert_eq!(offset_of(&t, &r, "l"), Ok(4));
    assert_eq!(bytes_in(&t, &r), Ok(12));
}

#[test]
fn aliases_share_representation_but_not_identity() {
    let mut t = TypeTable::default();
    let metres = Type::Named(t.defs.push(TypeDef {
        name: "METRES".into(),
        kind: TypeDefKind::Alias(Type::INT),
    }));
    assert_eq!(t.prim(&metres), Some(Prim::Int));
    assert_eq!(bytes_in(&t, &metres), Ok(4));
    assert!(!t.compatible(&Type::INT, &metres));
    assert!(t.compatible(
        &Type::array(None, Type::INT),
        &Type::array(Some(4), Type::INT)
    ));
    assert_eq!(t.display(&Type::array(Some(2), metres)), "[2]METRES");
}
