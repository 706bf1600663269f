//! A bounded FIFO that never allocates.

/// A first-in first-out queue of at most `N` `Copy` items, stored inline (a ring). A full
/// queue refuses a [`push`](Self::push); [`push_overwrite`](Self::push_overwrite) drops the
/// oldest instead (a sliding window).
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(bound(
    serialize = "T: serde::Serialize",
    deserialize = "T: serde::Deserialize<'de>"
))]
pub struct FixedQueue<T: Copy, const N: usize> {
    #[serde(with = "serde_big_array::BigArray")]
    items: [Option<T>; N],
    head: usize,
    len: usize,
}

impl<T: Copy, const N: usize> Default for FixedQueue<T, N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Copy, const N: usize> FixedQueue<T, N> {
    /// An empty queue.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            items: [None; N],
            head: 0,
            len: 0,
        }
    }

    /// How many items it holds at the most.
    #[must_use]
    pub const fn capacity(&self) -> usize {
        N
    }

    /// Items queued.
    #[must_use]
    pub const fn len(&self) -> usize {
        self.len
    }

    /// Whether nothing is queued.
    #[must_use]
    pub const fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Whether no item fits any more.
    #[must_use]
    pub const fn is_full(&self) -> bool {
        self.len >= N
    }

    /// Whether `count` more items fit.
    #[must_use]
    pub const fn has_room(&self, count: usize) -> bool {
        self.len + count <= N
    }

    fn slot(&self, index: usize) -> usize {
        if N == 0 { 0 } else { (self.head + index) % N }
    }

    /// Appends `item`; `false` (and nothing changes) when the queue is full.
    pub fn push(&mut self, item: T) -> bool {
        if self.is_full() {
            return false;
        }
        let slot = self.slot(self.len);
        if let Some(cell) = self.items.get_mut(slot) {
            *cell = Some(item);
            self.len += 1;
            return true;
        }
        false
    }

    /// Appends `item`, dropping and returning the oldest when the queue is full.
    pub fn push_overwrite(&mut self, item: T) -> Option<T> {
        let dropped = if self.is_full() { self.pop() } else { None };
        let _fits = self.push(item);
        dropped
    }

    /// Puts `item` before every other; `false` (and nothing changes) when full.
    pub fn push_front(&mut self, item: T) -> bool {
        if self.is_full() || N == 0 {
            return false;
        }
        self.head = (self.head + N - 1) % N;
        if let Some(cell) = self.items.get_mut(self.head) {
            *cell = Some(item);
        }
        self.len += 1;
        true
    }

    /// Appends as many of `items` as fit, in order; returns how many did.
    pub fn extend_from_slice(&mut self, items: &[T]) -> usize {
        items.iter().take_while(|&&item| self.push(item)).count()
    }

    /// The oldest item (the next out).
    #[must_use]
    pub fn front(&self) -> Option<T> {
        self.get(0)
    }

    /// The oldest item, to change it in place.
    pub fn front_mut(&mut self) -> Option<&mut T> {
        if self.len == 0 {
            return None;
        }
        let head = self.head;
        self.items.get_mut(head).and_then(Option::as_mut)
    }

    /// The newest item.
    #[must_use]
    pub fn back(&self) -> Option<T> {
        self.len.checked_sub(1).and_then(|last| self.get(last))
    }

    /// The newest item, to change it in place.
    pub fn back_mut(&mut self) -> Option<&mut T> {
        let last = self.len.checked_sub(1)?;
        let slot = self.slot(last);
        self.items.get_mut(slot).and_then(Option::as_mut)
    }

    /// The item `index` places behind the oldest.
    #[must_use]
    pub fn get(&self, index: usize) -> Option<T> {
        if index >= self.len {
            return None;
        }
        self.items.get(self.slot(index)).copied().flatten()
    }

    /// Removes and returns the oldest item.
    pub fn pop(&mut self) -> Option<T> {
        self.remove(0)
    }

    /// Removes and returns the item `index` places behind the oldest; the others keep their
    /// order.
    pub fn remove(&mut self, index: usize) -> Option<T> {
        let item = self.get(index)?;
        if index == 0 {
            let head = self.head;
            if let Some(cell) = self.items.get_mut(head) {
                *cell = None;
            }
            self.head = self.slot(1);
        } else {
            for k in index..self.len - 1 {
                let next = self.items.get(self.slot(k + 1)).copied().flatten();
                let slot = self.slot(k);
                if let Some(cell) = self.items.get_mut(slot) {
                    *cell = next;
                }
            }
            let last = self.slot(self.len - 1);
            if let Some(cell) = self.items.get_mut(last) {
                *cell = None;
            }
        }
        self.len -= 1;
        Some(item)
    }

    /// Where the oldest item that satisfies `matches` stands.
    #[must_use]
    pub fn position(&self, mut matches: impl FnMut(&T) -> bool) -> Option<usize> {
        self.iter().position(|item| matches(&item))
    }

    /// Keeps only the items for which `keep` is true, in order.
    pub fn retain(&mut self, mut keep: impl FnMut(&T) -> bool) {
        let mut kept = Self::new();
        for item in self.iter() {
            if keep(&item) {
                let _fits = kept.push(item);
            }
        }
        *self = kept;
    }

    /// Drops everything.
    pub fn clear(&mut self) {
        *self = Self::new();
    }

    /// Calls `change` on every item, oldest first.
    pub fn for_each_mut(&mut self, mut change: impl FnMut(&mut T)) {
        for index in 0..self.len {
            let slot = self.slot(index);
            if let Some(Some(item)) = self.items.get_mut(slot) {
                change(item);
            }
        }
    }

    /// The items, oldest first.
    pub fn iter(&self) -> impl DoubleEndedIterator<Item = T> + '_ {
        (0..self.len).filter_map(move |index| self.items.get(self.slot(index)).copied().flatten())
    }
}

#[cfg(test)]
mod tests {
    use super::FixedQueue;

    fn items<const N: usize>(queue: &FixedQueue<u32, N>) -> [Option<u32>; 8] {
        let mut out = [None; 8];
        for (slot, item) in out.iter_mut().zip(queue.iter()) {
            *slot = Some(item);
        }
        out
    }

    #[test]
    fn every_item_can_be_changed_in_place_across_the_wrap() {
        let mut queue = FixedQueue::<u32, 3>::new();
        assert!(queue.push(1) && queue.push(2) && queue.push(3));
        assert_eq!(queue.pop(), Some(1));
        assert!(queue.push(4));
        queue.for_each_mut(|item| *item *= 10);
        assert_eq!(items(&queue)[..4], [Some(20), Some(30), Some(40), None]);
    }

    #[test]
    fn fifo_refuses_when_full_and_wraps() {
        let mut queue = FixedQueue::<u32, 3>::new();
        assert!(queue.is_empty() && queue.has_room(3) && !queue.has_room(4));
        assert!(queue.push(1) && queue.push(2) && queue.push(3));
        assert!(queue.is_full());
        assert!(!queue.push(4));
        assert_eq!(queue.pop(), Some(1));
        assert!(queue.push(4)); // wraps around the ring
        assert_eq!(items(&queue)[..3], [Some(2), Some(3), Some(4)]);
        assert_eq!((queue.front(), queue.back()), (Some(2), Some(4)));
        assert_eq!(queue.pop(), Some(2));
        assert_eq!(queue.pop(), Some(3));
        assert_eq!(queue.pop(), Some(4));
        assert_eq!(queue.pop(), None);
    }

    #[test]
    fn remove_retain_and_push_front_keep_order() {
        let mut queue = FixedQueue::<u32, 5>::new();
        assert_eq!(queue.extend_from_slice(&[1, 2, 3, 4, 5, 6]), 5);
        assert_eq!(queue.pop(), Some(1));
        assert_eq!(queue.remove(1), Some(3));
        assert_eq!(items(&queue)[..3], [Some(2), Some(4), Some(5)]);
        assert_eq!(queue.position(|&x| x == 5), Some(2));
        assert!(queue.push_front(9));
        assert_eq!(items(&queue)[..4], [Some(9), Some(2), Some(4), Some(5)]);
        queue.retain(|&x| x % 2 == 1);
        assert_eq!(items(&queue)[..2], [Some(9), Some(5)]);
        assert_eq!(queue.len(), 2);
        assert_eq!(queue.remove(2), None);
        queue.clear();
        assert!(queue.is_empty());
    }

    #[test]
    fn push_overwrite_is_a_sliding_window() {
        let mut window = FixedQueue::<u32, 2>::new();
        assert_eq!(window.push_overwrite(1), None);
        assert_eq!(window.push_overwrite(2), None);
        assert_eq!(window.push_overwrite(3), Some(1));
        if let Some(newest) = window.back_mut() {
            *newest = 7;
        }
        if let Some(oldest) = window.front_mut() {
            *oldest += 1;
        }
        assert_eq!(items(&window)[..2], [Some(3), Some(7)]);
    }

    #[test]
    fn zero_capacity_refuses_everything() {
        let mut queue = FixedQueue::<u32, 0>::new();
        assert!(!queue.push(1) && !queue.push_front(1));
        assert_eq!(queue.pop(), None);
        assert_eq!(queue.push_overwrite(1), None);
    }
}
